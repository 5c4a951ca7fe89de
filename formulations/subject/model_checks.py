"""What a subject model file must hold beyond its fields' types: lengths a body can have, a
skeleton that is a forest, limbs between its own joints, rotations that are rotations.

A model is JSON a lab may edit by hand. Each of these was accepted and then failed far from
the file: a coordinate of 1e300 raised an IndexError inside the labeler, a spread of 1 m
made every point a candidate of every marker (17 s for 5 frames), a joint that closes a
loop broke the skeleton's dynamic programming (``tree_choice`` assumes a forest), a limb
between unknown joints or of negative length was printed as the subject's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from formulations.subject.model import SubjectModel

MAX_COORDINATE_MM = 5000.0  # a marker or joint centre in its segment's frame: within a body's size
MAX_SPREAD_MM = 100.0  # a marker moving more than this on its segment is not on a rigid segment
ROTATION_TOLERANCE = 1e-3  # |R R^T - I| and |det R - 1| of a rest rotation as JSON rounds it


def check_model(model: SubjectModel) -> None:
    """Raises ``ValueError`` (one line naming the entry) on a model no body has."""
    for segment in model.segments:
        _within(segment.coordinates, MAX_COORDINATE_MM, f"segment {segment.name!r}: coordinates")
        _within(segment.spread, MAX_SPREAD_MM, f"segment {segment.name!r}: spread")
    for joint in model.joints:
        _within(list(joint.centres), MAX_COORDINATE_MM, f"joint {joint.name!r}: centres")
        _within([joint.rms], MAX_SPREAD_MM, f"joint {joint.name!r}: rms")
        if joint.rest is not None and not _is_rotation(np.asarray(joint.rest, dtype=float)):
            raise ValueError(f"joint {joint.name!r}: rest is not a rotation (orthonormal, determinant 1)")
    for single in model.singles:
        # a single's distance to a segment spans joints: its sd may be a limb's swing, not a spread
        _within(single.sd, MAX_COORDINATE_MM, f"single marker {single.marker!r}: sd")
        _within(single.distances, MAX_COORDINATE_MM, f"single marker {single.marker!r}: distances")
    _check_forest(model)
    _check_limbs(model)


def _within(values: object, bound: float, what: str) -> None:
    if (np.abs(np.asarray(values, dtype=float)) > bound).any():
        raise ValueError(f"{what} must be within {bound:g} mm")


def _is_rotation(rest: np.ndarray) -> bool:
    return bool(np.abs(rest @ rest.T - np.eye(3)).max() <= ROTATION_TOLERANCE
                and abs(np.linalg.det(rest) - 1.0) <= ROTATION_TOLERANCE)


def _check_forest(model: SubjectModel) -> None:
    """Joints join two different segments, and no chain of joints comes back to where it began."""
    root = {segment.name: segment.name for segment in model.segments}

    def find(name: str) -> str:
        while root[name] != name:
            name = root[name]
        return name

    for joint in model.joints:
        a, b = joint.segments
        if a == b:
            raise ValueError(f"joint {joint.name!r} joins segment {a!r} to itself")
        if find(a) == find(b):
            raise ValueError(f"joint {joint.name!r} closes a loop of joints through {a!r} and {b!r} "
                             "(a skeleton's joints form a tree)")
        root[find(a)] = find(b)


def _check_limbs(model: SubjectModel) -> None:
    """A limb is a length >= 0 of its segment between two of that segment's joints."""
    joints = {joint.name: joint for joint in model.joints}
    for limb in model.limbs:
        what = f"limb of segment {limb.segment!r}"
        unknown = [name for name in limb.joints if name not in joints]
        if unknown:
            raise ValueError(f"{what}: joint {unknown[0]!r} is not in the model")
        if any(limb.segment not in joints[name].segments for name in limb.joints):
            raise ValueError(f"{what}: its joints {limb.joints[0]!r} and {limb.joints[1]!r} are not both on it")
        if not 0 <= limb.length <= MAX_COORDINATE_MM:
            raise ValueError(f"{what}: length must be >= 0 and within {MAX_COORDINATE_MM:g} mm, got {limb.length:g}")
