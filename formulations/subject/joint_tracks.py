"""Where the model's joint centres are in every frame of a labeled take: fill donors.

A segment posed by three or more of its own labeled markers (``marker_poses``, each within
``RIGID_WITHIN`` times its tolerance) puts the centre of each of its joints at

    y_j(f) = R_s(f) c_{j,s} + d_s(f),

each side giving its own track. Nothing is taken through the joint chain, and a centre
serves only the markers of the joint's other segment, so it is never derived from the gap
it helps to fill.

Why: a segment of three markers that loses two of them (a shank's LTB1 and LTB3, a foot's
LMT5 and LTOE) keeps one mate as a donor, and the take often has no marker on the joints; its
neighbouring segments' poses still place the knee and the ankle, which move with the shank
as rigidly as its own markers. Given to ``rigid_fill`` as extra tracks, such centres are
chosen as donors by the same distance spread as any marker. Only centres the model places
well serve (rms <= ``GUIDE_RMS_MM``): a poorly fitted centre, a noisy donor at the end of a
long lever, displaced better ones.

Measured (``bench/model_start.py``, fill RMSE / median of markers on segments of three or
more, against no centres): Rajagopal template 17.5 / 4.4 -> 15.4 / 4.0 mm, gait2354 9.6 /
3.5 -> 6.4 / 3.3, CMU 85_02 and 135_02 halves unchanged (10.8, 221; their fitted joints are
mostly above the bar); on a synthetic chain two of three markers lost for 40 frames, 46-83
-> 3.4 mm (``tests/test_joint_tracks.py``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.subject.geometry import JointGeometry, ModelGeometry
from formulations.subject.segment_pose import RIGID_WITHIN, marker_poses

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]
GUIDE_RMS_MM = 8.0  # a lab's joint-centre markers (5 mm) pass; CMU 85_02's fitted shoulders (10-22 mm) worsened its fill


def joint_tracks(geometry: ModelGeometry, names: list[str], positions: Array) -> tuple[Array, Mask]:
    """``(F, K, 3)`` each joint centre per frame of ``positions`` ``(F, N, 3)`` (markers
    ``names``, NaN where not labeled) as each of its two segments places it, NaN where that
    segment is not posed; and ``(K, N)`` the markers each may serve: those of the joint's
    other segment (on its own segment a centre only repeats its markers, with their noise)."""
    poses = marker_poses(geometry, geometry.in_model_order(names, positions), RIGID_WITHIN)
    joints = placed_well(geometry)
    sides = [(j.a, j.centre_a, j.b) for j in joints] + [(j.b, j.centre_b, j.a) for j in joints]
    centres = np.full((len(positions), len(sides), 3), np.nan)
    serves = np.zeros((len(sides), len(names)), dtype=bool)
    column = {name: i for i, name in enumerate(names)}
    for k, (s, centre, other) in enumerate(sides):
        at = np.einsum("fij,j->fi", poses.rotation[:, s], centre) + poses.origin[:, s]
        centres[poses.posed[:, s], k] = at[poses.posed[:, s]]
        serves[k, [column[geometry.names[m]] for m in geometry.segments[other].markers if geometry.names[m] in column]] = True
    return centres, serves


def placed_well(geometry: ModelGeometry) -> list[JointGeometry]:
    """The joints whose centre the model places within ``GUIDE_RMS_MM``."""
    return [joint for joint in geometry.joints if joint.rms <= GUIDE_RMS_MM]
