"""Joints no body has: a centre far from every marker of one of its two segments.

A joint of the body sits near both segments it joins: within a limb's length of each
segment's markers (the hip is ~100 mm from the ASIS, the knee a thigh's length from a
marker high on it, ~450 mm at most). A fit on a stretch where two segments barely move
against each other can still join them with a small RMS; its centre then lands wherever the
two rotations agree. Fitted on 600 frames of CMU 135_02, ``fit_subject`` joined the pelvis to
the left upper arm, the centre 509 mm from every pelvis marker; on the whole OpenSim
gait2354 walk, a thigh to a biceps marker (427 mm); on 03_rolling, a hand plate to a thigh
(801 mm). Whole-take fits of the other real takes keep their joints within 330 mm of both
segments, but for the basket sprint's wheelchair frame joined to a wheel sensor (415 mm: a
chair, not a body, and named too).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.subject.model import SubjectModel

LIMB_REACH_MM = 400.0  # a joint centre this far from every marker of a segment is not that segment's


@dataclass(frozen=True)
class FarJoint:
    """A joint whose centre is ``apart_mm`` from the nearest marker of ``segment``."""

    joint: str
    segment: str
    apart_mm: float


def far_joints(model: SubjectModel, reach_mm: float = LIMB_REACH_MM) -> list[FarJoint]:
    """The joints whose centre is beyond ``reach_mm`` of one of their segments' markers (the
    farther segment named), farthest first."""
    coordinates = {segment.name: np.asarray(segment.coordinates, dtype=float) for segment in model.segments}
    found = []
    for joint in model.joints:
        apart = [float(np.linalg.norm(coordinates[segment] - np.asarray(centre, dtype=float), axis=1).min())
                 for segment, centre in zip(joint.segments, joint.centres)]
        side = int(np.argmax(apart))
        if apart[side] > reach_mm:
            found.append(FarJoint(joint.name, joint.segments[side], apart[side]))
    return sorted(found, key=lambda far: -far.apart_mm)
