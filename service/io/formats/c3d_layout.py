"""A C3D file's layout, checked from its raw bytes before any C3D reader allocates for it.

A C3D file is 512-byte blocks: block 1 is the header, the parameter section starts at the
block named by header byte 0 and spans the number of blocks in its own byte 2, and the
data start at the block in header word 9. The header's 16-bit words give the point count
(word 2), the analog samples per frame (word 3) and the first and last frame (words 4-5).
Each parameter record declares a type ``t`` (-1 char, 1 byte, 2 int16, 4 float), at most
7 dimensions ``d_1..d_n`` and then holds ``|t| * prod(d_i)`` bytes and a description: all
of it must lie before the next record. A reader that trusts a broken count allocates for
it (or reads past its buffer), so every count is checked against the bytes really there.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from service.errors import InputError

BLOCK = 512
PREFIX_BYTES = 512 * BLOCK  # header + the largest parameter section a one-byte pointer can name
MIPS = 86  # processor-type byte of the only big-endian C3D flavour
_PROCESSORS = (84, 85, MIPS)  # Intel, DEC, MIPS
_TYPES = (-1, 1, 2, 4)
_MAX_DIMENSIONS = 7


@dataclass(frozen=True)
class C3dLayout:
    """What the header declares, once checked against the file's size."""

    points: int
    analog: int
    frames: int
    data_bytes: int  # bytes the declared frames occupy

    def check_limits(self, max_points: int | None, max_frames: int | None) -> None:
        """Raises ``InputError`` for no frames, or more points or frames than allowed (None: no limit)."""
        if self.frames == 0:  # ezc3d's own message names its internal Data::frame accessor
            raise InputError("the C3D file has no frames")
        if max_points is not None and self.points > max_points:
            raise InputError(f"{self.points} points exceeds the limit of {max_points} (limits.max_markers)")
        if max_frames is not None and self.frames > max_frames:
            raise InputError(f"{self.frames} frames exceeds the limit of {max_frames} (limits.max_frames)")


def c3d_layout(prefix: bytes, size: int) -> C3dLayout:
    """Check the header and parameter section in ``prefix`` (the file's first ``PREFIX_BYTES``).

    Args:
        prefix: The start of the file (all of it if shorter).
        size: The whole file's size in bytes.

    Raises:
        InputError: A header, parameter record or data size the file cannot hold.
    """
    if size < BLOCK or len(prefix) < BLOCK:
        raise InputError(f"not a C3D file ({size} bytes, shorter than its 512-byte header)")
    if prefix[1] != 0x50:
        raise InputError("not a C3D file (header byte 2 is not 0x50)")
    start = (prefix[0] - 1) * BLOCK
    if prefix[0] < 2 or start + 4 > len(prefix):
        raise InputError(f"C3D header points to parameter block {prefix[0]}, outside the file")
    blocks, processor = prefix[start + 2], prefix[start + 3]
    if processor not in _PROCESSORS:
        raise InputError(f"C3D parameter section names processor type {processor}, not 84, 85 or 86")
    order = ">" if processor == MIPS else "<"
    end = start + blocks * BLOCK
    if blocks == 0 or end > len(prefix):
        raise InputError(f"C3D parameter section of {blocks} blocks does not fit in the file")
    points, analog, first, last = struct.unpack_from(order + "4H", prefix, 2)
    (data_block,) = struct.unpack_from(order + "H", prefix, 16)
    if (data_block - 1) * BLOCK < end:
        raise InputError(f"C3D data block {data_block} overlaps the parameter section")
    _check_parameters(prefix, start + 4, end, order)
    frames = max(last - first + 1, 0)
    word = 4 if _negative_scale(prefix, processor) else 2  # float or integer samples
    data_bytes = frames * word * (4 * points + analog)
    available = size - (data_block - 1) * BLOCK
    if data_bytes > available:
        raise InputError(f"truncated C3D file ({size} of {(data_block - 1) * BLOCK + data_bytes} bytes)")
    return C3dLayout(points, analog, frames, data_bytes)


def _negative_scale(prefix: bytes, processor: int) -> bool:
    """The header's scale factor (words 7-8) is negative for float data; only its sign bit is read.

    The sign is the top bit of the float's most significant byte: byte 15 (Intel), 12 (MIPS),
    or 13 (DEC, whose floats swap their two 16-bit halves).
    """
    sign_byte = {84: 15, 85: 13, MIPS: 12}[processor]
    return bool(prefix[sign_byte] & 0x80)


def _check_parameters(data: bytes, at: int, end: int, order: str) -> None:
    """Walk the records from ``at``; each must end before the next and inside the section."""
    while at + 2 <= end:
        name_length, group = abs(struct.unpack_from("b", data, at)[0]), struct.unpack_from("b", data, at + 1)[0]
        if name_length == 0:
            return
        link = at + 2 + name_length  # the 16-bit offset to the next record is counted from here
        if link + 2 > end:
            raise InputError("C3D parameter section ends inside a record")
        (offset,) = struct.unpack_from(order + "h", data, link)
        following = link + offset if offset > 0 else end
        if offset < 0 or following > end:
            raise InputError(f"C3D parameter record at byte {at} points outside the parameter section")
        body_end = link + 2 + (_parameter_bytes(data, link + 2, following, at) if group > 0 else 0)
        if body_end >= following or body_end + 1 + data[body_end] > following:
            raise InputError(f"C3D parameter record at byte {at} overruns the next record")
        if offset == 0:
            return
        at = following


def _parameter_bytes(data: bytes, at: int, limit: int, record: int) -> int:
    """Bytes of a parameter's type, dimensions and values, starting at its type byte."""
    if at + 2 > limit:
        raise InputError(f"C3D parameter record at byte {record} overruns the next record")
    kind, count = struct.unpack_from("b", data, at)[0], data[at + 1]
    if kind not in _TYPES:
        raise InputError(f"C3D parameter record at byte {record} has data type {kind}, not -1, 1, 2 or 4")
    if count > _MAX_DIMENSIONS:
        raise InputError(f"C3D parameter record at byte {record} has {count} dimensions (at most 7)")
    if at + 2 + count > limit:
        raise InputError(f"C3D parameter record at byte {record} overruns the next record")
    return 2 + count + abs(kind) * math.prod(data[at + 2 : at + 2 + count])


def match_header_scale(path: str, scale: float) -> None:
    """Set the header's point scale (words 7-8) to ``scale``, the file's POINT:SCALE, in the
    file's own float format: ezc3d writes -1 there whatever the parameter says, and readers
    that hold the two to agree (py-c3d) refuse the file. Nothing is done to a DEC file (its
    float format is not IEEE) or where ``scale`` is not negative (float data)."""
    with open(path, "r+b") as f:
        header = f.read(BLOCK)
        if len(header) < BLOCK:  # a short file (a full disk): the writer's layout check says so
            return
        f.seek((header[0] - 1) * BLOCK + 3)
        read = f.read(1)
        processor = read[0] if read else None
        if processor not in (84, MIPS) or not scale < 0:
            return
        f.seek(12)
        f.write(struct.pack(">f" if processor == MIPS else "<f", scale))
