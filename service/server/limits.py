"""Request limits: the body size before anything is parsed, then the capture's dimensions."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Mapping

import numpy as np
from fastapi import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.capture.document import CaptureDocument
from service.errors import InputError
from service.server.auth import owner_of
from service.server.prescan import Structure, check_depth
from service.server.settings import Limits
from service.web.session import presented_token


class BodyLimit:
    """ASGI middleware: a body is read only from a known caller, and only up to ``max_bytes``.

    With tokens configured, a request without a valid bearer token (or, on a web page's
    path, session cookie) gets 401 before a byte of its body is read. A declared
    ``Content-Length`` over the limit is refused (413) at once; otherwise the body is read
    up to the limit (chunked uploads declare no length) and replayed to the app.
    Hand-written because Starlette and uvicorn have no body-size setting. A body that
    stalls for ``read_seconds`` answers 408.
    """

    def __init__(self, app: ASGIApp, max_bytes: int, owners: dict[str, str], read_seconds: float) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.owners = owners
        self.read_seconds = read_seconds  # the longest wait for the next piece of the body

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] in ("GET", "HEAD", "DELETE", "OPTIONS"):
            return await self.app(scope, receive, send)
        headers = dict(scope["headers"])
        try:
            owner_of(self.owners, presented_token(scope["path"], headers.get(b"authorization", b"").decode("latin-1"),
                                                  headers.get(b"cookie", b"").decode("latin-1")))
        except HTTPException as refused:
            return await _answer(send, refused.status_code, str(refused.detail), refused.headers or {})
        declared = headers.get(b"content-length", b"")
        if declared.isdigit() and int(declared) > self.max_bytes:
            return await self._refuse(send)
        chunks, size, more = [], 0, True
        while more:
            try:
                message = await asyncio.wait_for(receive(), self.read_seconds)
            except TimeoutError:  # a stalled body must not hold a connection and its memory forever
                return await _answer(send, 408, f"no request body data for {self.read_seconds:g} s "
                                                "(read_timeout_seconds)", {})
            if message["type"] == "http.disconnect":
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.max_bytes:
                return await self._refuse(send)
            chunks.append(chunk)
            more = message.get("more_body", False)
        body: bytes | None = b"".join(chunks)

        async def replay() -> Message:
            nonlocal body
            if body is None:
                return await receive()  # after the body: wait for the disconnect as usual
            message, body = {"type": "http.request", "body": body, "more_body": False}, None
            return message

        await self.app(scope, replay, send)

    async def _refuse(self, send: Send) -> None:
        message = f"the request body exceeds the limit of {self.max_bytes} bytes (limits.max_body_bytes)"
        await _answer(send, 413, message, {})


async def _answer(send: Send, status: int, message: str, headers: Mapping[str, str]) -> None:
    """A JSON ``{"message": ...}`` answer that closes the connection (the body stays unread)."""
    payload = json.dumps({"message": message}).encode()
    extra = [(name.lower().encode(), value.encode()) for name, value in headers.items()]
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(payload)).encode()),
                            (b"connection", b"close"), *extra]})
    await send({"type": "http.response.body", "body": payload})


def check_limits(document: CaptureDocument, limits: Limits) -> None:
    """Raise ``InputError`` naming the field and the limit a capture exceeds.

    Raises:
        InputError: ``frames: 120000 frames exceeds the limit of 100000 (limits.max_frames)``.
    """
    _at_most("frames", document.n_frames, "frames", limits.max_frames, "max_frames")
    _at_most("window", document.window, "frames", limits.max_window, "max_window")
    _at_most("markers", len(document.markers or []), "markers", limits.max_markers, "max_markers")
    if document.points is not None:
        for f, points in enumerate(document.points):
            _at_most(f"points.{f}", len(points), "points", limits.max_points_per_frame, "max_points_per_frame")
    if document.cameras is not None:
        _at_most("cameras", len(document.cameras), "cameras", limits.max_cameras, "max_cameras")
    for camera, frames in (document.detections or {}).items():
        for f, detections in enumerate(frames):
            _at_most(f"detections.{camera}.{f}", len(detections), "detections", limits.max_detections_per_camera,
                     "max_detections_per_camera")


def check_body_limits(body: bytes, limits: Limits) -> None:
    """``check_limits`` on a JSON body's bytes, before it is parsed (see ``prescan``).

    The counts are upper bounds of the parsed ones, so a body refused here would be refused
    after parsing too, with the same message; one that passes is parsed and checked again.

    Raises:
        InputError: Nesting deeper than ``prescan.MAX_DEPTH``, or a capture over a limit.
    """
    structure = check_depth(body, "body")
    values = structure.top_level_values(max_fields=len(CaptureDocument.model_fields))
    sizes = {key: _Sizes(structure, span) for key, span in values.items()}
    points, detections = sizes.get("points"), sizes.get("detections")
    frames = [points.count(2)] if points else []
    frames += list(detections.per(3, 2)) if detections else []
    _at_most("frames", max(frames, default=0), "frames", limits.max_frames, "max_frames")
    if "markers" in sizes:
        _at_most("markers", sizes["markers"].count(2), "markers", limits.max_markers, "max_markers")
    if points:
        per_frame = points.per(3, 2)
        for f in np.flatnonzero(per_frame > limits.max_points_per_frame)[:1]:
            _at_most(f"points.{f}", int(per_frame[f]), "points", limits.max_points_per_frame, "max_points_per_frame")
    if "cameras" in sizes:
        _at_most("cameras", sizes["cameras"].count(2), "cameras", limits.max_cameras, "max_cameras")
    if detections:
        _check_detections(detections, limits.max_detections_per_camera)


class _Sizes:
    """Element counts inside one top-level value, whose own elements are at depth 2."""

    def __init__(self, structure: Structure, span: tuple[int, int]) -> None:
        self.structure, (self.start, self.stop) = structure, span

    def commas(self, depth: int) -> np.ndarray:
        return self.structure.commas(self.start, self.stop, depth)

    def count(self, depth: int) -> int:
        """Elements at ``depth`` in all (commas + 1)."""
        return int(self.commas(depth).sum()) + 1

    def per(self, depth: int, *group_depths: int) -> np.ndarray:
        """Elements at ``depth`` in each container that commas at ``group_depths`` separate."""
        ends = np.logical_or.reduce([self.commas(d) for d in group_depths])
        groups = np.cumsum(ends)
        return np.bincount(groups[self.commas(depth)], minlength=int(groups[-1]) + 1 if len(groups) else 1) + 1


def _check_detections(detections: _Sizes, limit: int) -> None:
    """``detections.<camera>.<frame>``: elements at depth 4 per frame (depth 3) of each camera (depth 2)."""
    counts = detections.per(4, 2, 3)
    over = np.flatnonzero(counts > limit)
    if not len(over):
        return
    camera_ends, frame_ends = detections.commas(2), detections.commas(3)
    # The frame's first token: the comma that ends the frame (or camera) before it, or the key's colon.
    first = int(np.flatnonzero(np.cumsum(camera_ends | frame_ends) == over[0])[0])
    camera = int(camera_ends[: first + 1].sum())
    camera_start = int(np.flatnonzero(camera_ends)[camera - 1]) if camera else 0
    frame = int(frame_ends[camera_start : first + 1].sum())
    colon = detections.structure.colons(detections.start, detections.stop, 2)[camera]
    name = detections.structure.key_before(int(colon))
    _at_most(f"detections.{name}.{frame}", int(counts[over[0]]), "detections", limit, "max_detections_per_camera")


def _at_most(field: str, count: int, what: str, limit: int, name: str) -> None:
    if count > limit:
        raise InputError(f"{field}: {count} {what} exceeds the limit of {limit} (limits.{name})")
