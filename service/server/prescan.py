"""A JSON body's structure, counted from its bytes before it is parsed.

Parsing a 60 MiB capture document builds about a gigabyte of Python objects; the counts
the limits need (nesting depth, frames, points per frame, ...) can be read from the bytes.
Once ``\\\\`` and ``\\"`` are blanked (same length), every ``"`` left opens or closes a
string, so a byte is inside a string iff an odd number of quotes precede it. Outside
strings ``[``/``{`` open a level and ``]``/``}`` close one; a ``,`` at depth d separates
the elements of the container whose contents are at depth d, so a container holds at most
(its commas + 1) elements. The scan is numpy over 8 MiB chunks: its memory is about the
body's size, not the document's. Hand-written rather than a streaming parser (ijson): that
would still hand every number of a 60 MiB body to Python one event at a time, tens of
millions of events, where these counts need one vectorised pass over the bytes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from service.errors import InputError

MAX_DEPTH = 32  # a capture document nests 5 deep (detections.camera.frame.detection.xy)
_CHUNK = 8 * 2**20
_STRUCTURAL = np.zeros(256, dtype=bool)
_STRUCTURAL[list(b"[]{},:")] = True
_OPEN, _CLOSE, _COMMA, _COLON = np.frombuffer(b"[{", np.uint8), np.frombuffer(b"]}", np.uint8), ord(","), ord(":")


@dataclass(frozen=True)
class Structure:
    """Every structural byte outside strings: its position, the byte, and the depth after it."""

    body: bytes
    text: bytes  # the body with escapes blanked: quotes in it are string ends only
    position: np.ndarray
    kind: np.ndarray
    depth: np.ndarray

    @classmethod
    def of(cls, body: bytes) -> Structure:
        text = body.replace(b"\\\\", b"__").replace(b'\\"', b"__") if b"\\" in body else body
        data = np.frombuffer(text, dtype=np.uint8)
        positions, odd = [], 0
        index = np.int32 if len(data) < 2**31 else np.int64  # half the memory for any body under 2 GiB
        for start in range(0, len(data), _CHUNK):
            chunk = data[start : start + _CHUNK]
            inside = (np.cumsum(chunk == ord('"'), dtype=np.uint8) + odd) & 1  # parity survives the wrap
            odd = int(inside[-1])
            positions.append((np.flatnonzero(_STRUCTURAL[chunk] & (inside == 0)) + start).astype(index))
        position = np.concatenate(positions) if positions else np.zeros(0, dtype=index)
        kind = data[position]
        step = np.isin(kind, _OPEN).astype(np.int32) - np.isin(kind, _CLOSE).astype(np.int32)
        return cls(body, text, position, kind, np.cumsum(step, dtype=np.int32))

    def max_depth(self) -> int:
        return int(self.depth.max(initial=0))

    def key_before(self, token: int) -> str:
        """The object key whose ``:`` is ``token``, decoded ("?" if it is not a JSON string)."""
        end = self.text.rfind(b'"', 0, int(self.position[token]))
        try:
            return str(json.loads(self.body[self.text.rfind(b'"', 0, end) : end + 1]))
        except ValueError:
            return "?"

    def commas(self, start: int, stop: int, depth: int) -> np.ndarray:
        """Whether each token in ``[start, stop)`` is a comma at ``depth``."""
        return (self.kind[start:stop] == _COMMA) & (self.depth[start:stop] == depth)

    def colons(self, start: int, stop: int, depth: int) -> np.ndarray:
        """Token indices of the ``:`` at ``depth`` in ``[start, stop)``."""
        return start + np.flatnonzero((self.kind[start:stop] == _COLON) & (self.depth[start:stop] == depth))

    def top_level_values(self, max_fields: int) -> dict[str, tuple[int, int]]:
        """Top-level key -> its value's token range (from its ``:`` to the ``,`` or ``}`` after it).

        Raises:
            InputError: More than ``max_fields`` top-level keys.
        """
        colons = self.colons(0, len(self.kind), 1)
        if len(colons) > max_fields:
            raise InputError(f"body: {len(colons)} top-level fields; a capture document has at most {max_fields}")
        ends = np.flatnonzero(((self.kind == _COMMA) & (self.depth == 1)) | (self.depth == 0))
        stops = ends[np.minimum(np.searchsorted(ends, colons), len(ends) - 1)] if len(ends) else colons
        return {self.key_before(int(colon)): (int(colon), int(stop)) for colon, stop in zip(colons, stops, strict=True)}


def check_depth(body: bytes, field: str) -> Structure:
    """The body's structure; ``InputError`` if it nests deeper than ``MAX_DEPTH``."""
    structure = Structure.of(body)
    if structure.max_depth() > MAX_DEPTH:
        raise InputError(f"{field}: nested deeper than {MAX_DEPTH} levels")
    return structure
