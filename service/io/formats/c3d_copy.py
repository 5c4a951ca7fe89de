"""The copies of a C3D input that a relabel keeps and writes into.

ezc3d reads a file into C++ objects, one per point and frame, and gives numpy arrays and
parameter dictionaries on top; its ``write`` builds a new file from the arrays and
parameters alone. What a relabel keeps of its input and what it writes into are copies of
that Python side only, and of what the output changes only.
"""

from __future__ import annotations

import copy

import ezc3d

SHARED_DATA = ("analogs", "rotations", "platform")  # never written into: ``with_confidence`` replaces the analog array


def detached(c3d: ezc3d.c3d) -> ezc3d.c3d:
    """``c3d`` without the C++ file it was read into, which nothing reads again: 65 of the
    86 MB a 10,000-frame, 41-point file takes. (As ezc3d's own copy: a new, empty C++ file,
    the Python side copied; what ``write_c3d`` has always written from. Its data arrays,
    which numpy owns, are taken over, not copied: the reader drops ``c3d``.)"""
    return _copy(c3d, tuple(c3d["data"]))


def writable(c3d: ezc3d.c3d) -> ezc3d.c3d:
    """A copy of ``c3d`` for an output to write its labels into, as ezc3d's ``deepcopy`` makes
    one, but with the analog samples, rotations and force platforms shared, not copied: a
    relabel writes points, their residuals and masks and parameters, and replaces the analog
    array whole (``with_confidence``), so the input (which a server may write again) stays
    as read. At 1,000 Hz analog beside 100 Hz points the analog array is most of a file."""
    return _copy(c3d, SHARED_DATA)


def _copy(c3d: ezc3d.c3d, shared: tuple[str, ...]) -> ezc3d.c3d:
    """ezc3d's ``deepcopy`` of ``c3d`` with the data arrays named in ``shared`` the same objects."""
    new = ezc3d.c3d()
    new.extract_forceplat_data = c3d.extract_forceplat_data
    for part in c3d["header"]:
        for key in c3d["header"][part]:
            new["header"][part][key] = copy.deepcopy(c3d["header"][part][key])
    for group in c3d["parameters"]:
        new["parameters"][group] = copy.deepcopy(c3d["parameters"][group])
    for key in c3d["data"]:
        value = c3d["data"][key]
        new["data"][key] = value if key in shared else copy.deepcopy(value)
    return new
