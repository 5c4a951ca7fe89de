"""POINT parameters a C3D copy keeps consistent with the points it writes."""

from __future__ import annotations

import re

import ezc3d
import numpy as np

from service.errors import InputError

PARAMETER_ENTRIES = 255  # a C3D parameter's dimension is one byte: past it, LABELS2, LABELS3 ...
LAST_FRAME = 65535  # the header numbers frames in 16-bit words


def append_entries(c3d: ezc3d.c3d, stem: str, entries: list[str]) -> None:
    """``entries`` after the last of POINT's ``stem``, ``stem``2, ... (none: nothing to keep),
    filling each to ``PARAMETER_ENTRIES`` and going on in a new one, as C3D readers expect."""
    point = c3d["parameters"]["POINT"]
    groups = [k for k in point if re.fullmatch(rf"{stem}\d*", k)]
    if not groups:
        return
    last = max(groups, key=lambda k: int(k[len(stem):] or 1))
    values = list(point[last]["value"])
    room = max(PARAMETER_ENTRIES - len(values), 0)
    point[last]["value"] = values + entries[:room]
    number, rest = int(last[len(stem):] or 1), entries[room:]
    while rest:
        number += 1
        c3d.add_parameter("POINT", f"{stem}{number}", rest[:PARAMETER_ENTRIES])
        rest = rest[PARAMETER_ENTRIES:]


def float_scale(c3d: ezc3d.c3d) -> float:
    """POINT:SCALE made negative (ezc3d writes float data whatever the input stored), its
    magnitude kept: in float files it scales the residual byte."""
    scale = c3d["parameters"]["POINT"]["SCALE"]
    scale["value"] = -np.abs(np.asarray(scale["value"], dtype=float))
    return float(scale["value"][0])


def check_frame_numbers(first: int, frames: int) -> int:
    """``first``, the header's first frame number, if ``frames`` frames numbered from it fit.

    Raises:
        InputError: they run past ``LAST_FRAME`` (a trimmed long take's own numbers): ezc3d
            wrote them wrapped, and the file read back as truncated.
    """
    if first + frames - 1 > LAST_FRAME:
        raise InputError(f"a C3D numbers frames up to {LAST_FRAME} and these run from {first} to {first + frames - 1}; "
                         "write .trc or .csv, which keep any frame number")
    return first
