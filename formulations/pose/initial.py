"""A starting pose from three body points, and body proportions from triangulated keypoints.

The root frame is set from the pelvis centre h (mid-hips), its left axis from RHip to LHip
and its up axis towards the neck n: z = (n - h) / |n - h|, y = the left axis with its z
component removed, x = y x z. Its angles (a, b, c) solve R = R_z(a) R_y(b) R_x(c):
b = -asin R_20, c = atan2(R_21, R_22), a = atan2(R_10, R_00). Every joint starts at rest.

The proportions are a calibration of the subject from the take's own triangulated keypoints, one
value per length over the whole take (medians over frames, so a frame's bad triangulation does
not move them): bone lengths as distances; the clavicle's drop as the median height of the neck
keypoint above the mid-shoulders along the trunk (pelvis to neck); the nose from the triangle
neck, head top, nose (sides a = |neck head|, b = |neck nose|, c = |head nose|: up = (a^2 + b^2 -
c^2) / 2a along the neck, forward = sqrt(b^2 - up^2)); the foot from the triangle ankle, heel, toe
with heel and toe at one depth h below the ankle (|ankle heel|^2 = back^2 + h^2, |ankle toe|^2 =
forward^2 + h^2, |heel toe| = back + forward, so forward - back = (|ankle toe|^2 - |ankle heel|^2)
/ |heel toe|).
"""

from __future__ import annotations

import numpy as np

from formulations.errors import FormulationError
from formulations.pose.body import TRANSLATION_DOF, BodyModel
from formulations.pose.human import Proportions
from formulations.pose.rotation import Array


def standing_start(model: BodyModel, right_hip: Array, left_hip: Array, neck: Array) -> Array:
    """``(D,)`` configuration with the root ("zyx" axes) at the mid-hips, facing as the three points say."""
    if model.nodes[0].axes != "zyx":
        raise FormulationError("initial pose: the root must turn about z, y, x in that order")
    if not np.isfinite(np.concatenate([right_hip, left_hip, neck])).all():
        raise FormulationError("initial pose: hips and neck must all be seen to start")
    centre = 0.5 * (right_hip + left_hip)
    up = (neck - centre) / np.linalg.norm(neck - centre)
    left = (left_hip - right_hip) - ((left_hip - right_hip) @ up) * up
    left /= np.linalg.norm(left)
    frame = np.column_stack([np.cross(left, up), left, up])
    start = np.zeros(model.dof)
    start[:TRANSLATION_DOF] = centre - np.asarray(model.nodes[0].offset)
    start[TRANSLATION_DOF:TRANSLATION_DOF + 3] = (
        np.arctan2(frame[1, 0], frame[0, 0]), -np.arcsin(np.clip(frame[2, 0], -1, 1)), np.arctan2(frame[2, 1], frame[2, 2]))
    return start


def _median_distance(points: dict[str, Array], pairs: list[tuple[str, str]]) -> float | None:
    """Median over frames and over the pairs (left and right) of |A - B|; None if never seen."""
    distances = [np.linalg.norm(points[a] - points[b], axis=-1) for a, b in pairs if a in points and b in points]
    values = np.concatenate(distances) if distances else np.empty(0)
    values = values[np.isfinite(values)]
    return float(np.median(values)) if len(values) else None


def fit_proportions(points: dict[str, Array], metres_per_unit: float) -> Proportions:
    """Segment lengths as the median triangulated distances between named keypoints ``(F, 3)``
    (in a unit of ``metres_per_unit`` m); lengths never seen keep the default body's."""
    default = Proportions()
    if "RHip" in points and "LHip" in points:
        points = {**points, "CHip": 0.5 * (points["RHip"] + points["LHip"])}

    def length(pairs: list[tuple[str, str]], fallback: float, half: bool = False) -> float:
        found = _median_distance(points, pairs)
        return fallback if found is None else found * metres_per_unit * (0.5 if half else 1.0)

    head = length([("Neck", "Head")], default.neck_to_head_top)
    nose = _nose(head, length([("Neck", "Nose")], np.nan), length([("Head", "Nose")], np.nan))
    foot = _foot(length([("RAnkle", "RHeel"), ("LAnkle", "LHeel")], np.nan),
                 length([("RAnkle", "RBigToe"), ("LAnkle", "LBigToe")], np.nan),
                 length([("RHeel", "RBigToe"), ("LHeel", "LBigToe")], np.nan))
    drop = _shoulder_drop(points)
    return Proportions(
        foot=foot[0] if foot else default.foot,
        heel_back=foot[1] if foot else default.heel_back,
        ankle_height=foot[2] if foot else default.ankle_height,
        shoulder_drop=default.shoulder_drop if drop is None else drop * metres_per_unit,
        nose_forward=nose[0] if nose else default.nose_forward,
        nose_up=nose[1] if nose else default.nose_up,
        hip_half_width=length([("RHip", "LHip")], default.hip_half_width, half=True),
        thigh=length([("RHip", "RKnee"), ("LHip", "LKnee")], default.thigh),
        shank=length([("RKnee", "RAnkle"), ("LKnee", "LAnkle")], default.shank),
        trunk=length([("CHip", "Neck")], default.trunk),
        shoulder_half_width=length([("RShoulder", "LShoulder")], default.shoulder_half_width, half=True),
        upper_arm=length([("RShoulder", "RElbow"), ("LShoulder", "LElbow")], default.upper_arm),
        forearm=length([("RElbow", "RWrist"), ("LElbow", "LWrist")], default.forearm),
        neck_to_head_top=head,
    )


def _nose(head: float, neck_nose: float, head_nose: float) -> tuple[float, float] | None:
    """(forward, up) of the nose from the neck (module doc), None if unseen or not a triangle."""
    up = (head ** 2 + neck_nose ** 2 - head_nose ** 2) / (2.0 * head)
    if not np.isfinite(up) or neck_nose ** 2 <= up ** 2:
        return None
    return float(np.sqrt(neck_nose ** 2 - up ** 2)), float(up)


def _foot(ankle_heel: float, ankle_toe: float, heel_toe: float) -> tuple[float, float, float] | None:
    """(forward, back, depth) of toe and heel from the ankle (module doc), None if unseen or inconsistent."""
    difference = (ankle_toe ** 2 - ankle_heel ** 2) / heel_toe
    forward, back = 0.5 * (heel_toe + difference), 0.5 * (heel_toe - difference)
    if not np.isfinite(forward) or back < 0.0 or ankle_heel ** 2 <= back ** 2:
        return None
    return float(forward), float(back), float(np.sqrt(ankle_heel ** 2 - back ** 2))


def _shoulder_drop(points: dict[str, Array]) -> float | None:
    """Median height of the neck keypoint above the mid-shoulders along the pelvis-to-neck axis."""
    if not {"CHip", "Neck", "RShoulder", "LShoulder"} <= set(points):
        return None
    axis = points["Neck"] - points["CHip"]
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    heights = np.einsum("fi,fi->f", points["Neck"] - 0.5 * (points["RShoulder"] + points["LShoulder"]), axis)
    heights = heights[np.isfinite(heights)]
    return float(np.median(heights)) if len(heights) else None
