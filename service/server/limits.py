"""Request limits: the body size before anything is parsed, then the capture's dimensions."""

from __future__ import annotations

import json

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.capture.document import CaptureDocument
from service.errors import InputError
from service.server.settings import Limits


class BodyLimit:
    """ASGI middleware: a body over ``max_bytes`` gets 413 before the app parses a byte of it.

    A declared ``Content-Length`` over the limit is refused at once; otherwise the body
    is read up to the limit (chunked uploads declare no length) and replayed to the app.
    Hand-written because Starlette and uvicorn have no body-size setting.
    """

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] in ("GET", "HEAD", "DELETE", "OPTIONS"):
            return await self.app(scope, receive, send)
        declared = dict(scope["headers"]).get(b"content-length", b"")
        if declared.isdigit() and int(declared) > self.max_bytes:
            return await self._refuse(send)
        chunks, size, more = [], 0, True
        while more:
            message = await receive()
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
        payload = json.dumps({"message": message}).encode()
        await send({"type": "http.response.start", "status": 413,
                    "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(payload)).encode()),
                                (b"connection", b"close")]})
        await send({"type": "http.response.body", "body": payload})


def check_limits(document: CaptureDocument, limits: Limits) -> None:
    """Raise ``InputError`` naming the field and the limit a capture exceeds.

    Raises:
        InputError: ``frames: 120000 frames exceeds the limit of 100000 (limits.max_frames)``.
    """
    _at_most("frames", document.n_frames, "frames", limits.max_frames, "max_frames")
    _at_most("markers", len(document.markers), "markers", limits.max_markers, "max_markers")
    if document.points is not None:
        for f, points in enumerate(document.points):
            _at_most(f"points.{f}", len(points), "points", limits.max_points_per_frame, "max_points_per_frame")
    if document.cameras is not None:
        _at_most("cameras", len(document.cameras), "cameras", limits.max_cameras, "max_cameras")
    for camera, frames in (document.detections or {}).items():
        for f, detections in enumerate(frames):
            _at_most(f"detections.{camera}.{f}", len(detections), "detections", limits.max_detections_per_camera,
                     "max_detections_per_camera")


def _at_most(field: str, count: int, what: str, limit: int, name: str) -> None:
    if count > limit:
        raise InputError(f"{field}: {count} {what} exceeds the limit of {limit} (limits.{name})")
