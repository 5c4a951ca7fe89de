"""The default human body: 33 DOF as the paper's Fig. 1, joints named as BODY_25B keypoints.

Body frame at rest: x forward, y to the body's left, z up; standing upright, arms hanging.
The pelvis ``CHip`` is the 6-DOF root; a lumbar socket ``Spine`` turns the trunk; the neck is a
saddle; each clavicle a saddle at the top of the trunk; shoulders and hips sockets; elbows,
knees and ankles hinges; wrists, toes, heels, head top and nose are fixed ends. 6 + 3 + 2 +
2 x (2 + 3 + 1) + 2 x (3 + 1 + 1) = 33 DOF. Hinges bend about y: a knee's positive angle swings
the shank backwards, an elbow's negative angle swings the forearm forwards.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.pose.body import BodyModel, Cone, Node

DEG = np.pi / 180.0


@dataclass(frozen=True)
class Proportions:
    """Segment lengths and half-widths of the default body, metres (an adult of about 1.75 m).

    ``trunk`` runs from the pelvis to the neck joint (BODY_25B's neck keypoint is at the top of the
    neck); each clavicle runs from there ``shoulder_half_width`` out and ``shoulder_drop`` down to its
    shoulder; the nose is ``nose_forward`` ahead of and ``nose_up`` above the neck joint; the toes
    ``foot`` ahead of the ankle, the heel ``heel_back`` behind it, both ``ankle_height`` below it."""

    hip_half_width: float = 0.09
    thigh: float = 0.42
    shank: float = 0.42
    foot: float = 0.15
    ankle_height: float = 0.07
    heel_back: float = 0.05
    trunk: float = 0.50
    shoulder_drop: float = 0.05
    shoulder_half_width: float = 0.18
    upper_arm: float = 0.29
    forearm: float = 0.26
    neck_to_head_top: float = 0.24
    nose_forward: float = 0.10
    nose_up: float = 0.12


def human_model(p: Proportions = Proportions()) -> BodyModel:
    """The default body with proportions ``p`` (metres; ``BodyModel.scaled`` for other units)."""
    nodes: list[Node] = []

    def add(name: str, parent: str | None, offset: tuple[float, float, float], axes: str = "",
            limits: tuple[tuple[float, float], ...] = ()) -> None:
        lower = tuple(lo * DEG for lo, _ in limits)
        upper = tuple(hi * DEG for _, hi in limits)
        nodes.append(Node(name, -1 if parent is None else [n.name for n in nodes].index(parent), offset, axes, lower, upper))

    # Any pelvis orientation: R_z(a) R_y(b) R_x(c) with b in [-90, 90] covers them all, and leaving
    # a and c unbounded keeps a turning subject's heading from being clipped at +-180 degrees.
    add("CHip", None, (0.0, 0.0, 0.0), "zyx", ((-np.inf, np.inf), (-90, 90), (-np.inf, np.inf)))
    add("Spine", "CHip", (0.0, 0.0, 0.0), "zxy", ((-40, 40), (-30, 30), (-30, 90)))
    add("Neck", "Spine", (0.0, 0.0, p.trunk), "xy", ((-40, 40), (-50, 60)))
    add("Head", "Neck", (0.0, 0.0, p.neck_to_head_top))
    add("Nose", "Neck", (p.nose_forward, 0.0, p.nose_up))
    for side, sign in (("R", -1.0), ("L", 1.0)):
        # Abduction about x is mirrored between sides: the limits are flipped with the sign.
        def mirrored(lo: float, hi: float, s: float = sign) -> tuple[float, float]:
            return (lo, hi) if s > 0 else (-hi, -lo)

        add(f"{side}Clavicle", "Spine", (0.0, 0.0, p.trunk), "xy", (mirrored(-10, 30), (-20, 20)))
        add(f"{side}Shoulder", f"{side}Clavicle", (0.0, sign * p.shoulder_half_width, -p.shoulder_drop), "zxy",
            (mirrored(-90, 90), mirrored(-30, 180), (-180, 60)))
        add(f"{side}Elbow", f"{side}Shoulder", (0.0, 0.0, -p.upper_arm), "y", ((-160, 0),))
        add(f"{side}Wrist", f"{side}Elbow", (0.0, 0.0, -p.forearm))
        add(f"{side}Hip", "CHip", (0.0, sign * p.hip_half_width, 0.0), "zxy",
            (mirrored(-45, 45), mirrored(-30, 60), (-130, 30)))
        add(f"{side}Knee", f"{side}Hip", (0.0, 0.0, -p.thigh), "y", ((0, 160),))
        add(f"{side}Ankle", f"{side}Knee", (0.0, 0.0, -p.shank), "y", ((-30, 50),))
        add(f"{side}BigToe", f"{side}Ankle", (p.foot, -sign * 0.01, -p.ankle_height))
        add(f"{side}SmallToe", f"{side}Ankle", (0.8 * p.foot, sign * 0.04, -p.ankle_height))
        add(f"{side}Heel", f"{side}Ankle", (-p.heel_back, 0.0, -p.ankle_height))
    names = [n.name for n in nodes]

    def cone(a: str, b: str, r0: float, r1: float) -> Cone:
        return Cone(names.index(a), names.index(b), (r0, r1))

    cones = [cone("CHip", "Neck", 0.15, 0.13), cone("Neck", "Head", 0.06, 0.09)]
    for s in "RL":
        cones += [
            cone(f"{s}Clavicle", f"{s}Shoulder", 0.06, 0.055),
            cone(f"{s}Shoulder", f"{s}Elbow", 0.055, 0.045), cone(f"{s}Elbow", f"{s}Wrist", 0.045, 0.035),
            cone(f"{s}Hip", f"{s}Knee", 0.085, 0.055), cone(f"{s}Knee", f"{s}Ankle", 0.055, 0.04),
            cone(f"{s}Heel", f"{s}BigToe", 0.035, 0.03),
        ]
    return BodyModel(tuple(nodes), tuple(cones))
