"""Body geometry of the demo figure: a kinematic tree of segments and the markers on them.

Every segment frame has x forward, y to the figure's left and z up in the neutral
pose, with its origin at the joint that connects it to its parent. Lengths are in
millimetres and sized for a person about 1.75 m tall. Only the left side is written
out; the right side is its mirror image (y negated), so the two cannot drift apart.
"""

from __future__ import annotations

from typing import NamedTuple

Vec = tuple[float, float, float]


class Segment(NamedTuple):
    """One rigid body part: its parent and where their joint sits in the parent's frame."""

    name: str
    parent: str | None
    joint: Vec


class Marker(NamedTuple):
    """One marker: its label, the segment it rides on and its offset in that segment's frame."""

    name: str
    segment: str
    offset: Vec


_CENTRE_SEGMENTS = (
    Segment("pelvis", None, (0.0, 0.0, 0.0)),
    Segment("thorax", "pelvis", (-20.0, 0.0, 100.0)),
    Segment("head", "thorax", (10.0, 0.0, 450.0)),
)

# Parents come before children, so one pass in this order is forward kinematics.
_LEFT_SEGMENTS = (
    Segment("Lthigh", "pelvis", (0.0, 90.0, -60.0)),
    Segment("Lshank", "Lthigh", (0.0, 0.0, -420.0)),
    Segment("Lfoot", "Lshank", (0.0, 0.0, -410.0)),
    Segment("Lupperarm", "thorax", (-10.0, 180.0, 380.0)),
    Segment("Lforearm", "Lupperarm", (0.0, 0.0, -290.0)),
    Segment("Lhand", "Lforearm", (0.0, 0.0, -250.0)),
)

# Plug-in Gait is deliberately asymmetric at the back (RBAK only) so a labeller can
# tell the figure's left from its right.
_CENTRE_MARKERS = (
    Marker("C7", "thorax", (-70.0, 0.0, 440.0)),
    Marker("T10", "thorax", (-110.0, 0.0, 220.0)),
    Marker("CLAV", "thorax", (70.0, 0.0, 380.0)),
    Marker("STRN", "thorax", (110.0, 0.0, 220.0)),
    Marker("RBAK", "thorax", (-100.0, -80.0, 330.0)),
)

_LEFT_HEAD_MARKERS = (
    Marker("LFHD", "head", (80.0, 55.0, 170.0)),
    Marker("LBHD", "head", (-90.0, 50.0, 150.0)),
)

_LEFT_BODY_MARKERS = (
    Marker("LSHO", "thorax", (0.0, 180.0, 425.0)),
    Marker("LUPA", "Lupperarm", (-20.0, 50.0, -150.0)),
    Marker("LELB", "Lupperarm", (0.0, 40.0, -290.0)),
    Marker("LFRM", "Lforearm", (-20.0, 35.0, -130.0)),
    Marker("LWRA", "Lforearm", (30.0, 0.0, -250.0)),
    Marker("LWRB", "Lforearm", (-30.0, 0.0, -250.0)),
    Marker("LFIN", "Lhand", (15.0, 20.0, -80.0)),
    Marker("LASI", "pelvis", (90.0, 120.0, 30.0)),
    Marker("LPSI", "pelvis", (-90.0, 50.0, 40.0)),
    Marker("LTHI", "Lthigh", (15.0, 75.0, -220.0)),
    Marker("LKNE", "Lthigh", (0.0, 55.0, -420.0)),
    Marker("LTIB", "Lshank", (15.0, 55.0, -200.0)),
    Marker("LANK", "Lshank", (0.0, 40.0, -410.0)),
    Marker("LHEE", "Lfoot", (-70.0, 0.0, -40.0)),
    Marker("LTOE", "Lfoot", (140.0, 10.0, -55.0)),
)


def mirror_name(name: str) -> str:
    """The right-side counterpart of a left-side name (``LKNE`` -> ``RKNE``)."""
    return "R" + name[1:] if name.startswith("L") else name


def _mirror(v: Vec) -> Vec:
    return (v[0], -v[1], v[2])


def _right_segment(left: Segment) -> Segment:
    parent = mirror_name(left.parent) if left.parent else None
    return Segment(mirror_name(left.name), parent, _mirror(left.joint))


def _pairs(left: tuple[Marker, ...]) -> tuple[Marker, ...]:
    return tuple(
        marker
        for m in left
        for marker in (m, Marker(mirror_name(m.name), mirror_name(m.segment), _mirror(m.offset)))
    )


SEGMENTS: tuple[Segment, ...] = (
    _CENTRE_SEGMENTS + _LEFT_SEGMENTS + tuple(_right_segment(s) for s in _LEFT_SEGMENTS)
)

# Column order reads head to toe, left before right, as Vicon exports do.
MARKERS: tuple[Marker, ...] = (
    _pairs(_LEFT_HEAD_MARKERS) + _CENTRE_MARKERS + _pairs(_LEFT_BODY_MARKERS)
)
