"""A rigid segment in motion with a neighbour swinging about one of its markers: the scene the
mirror and pair-evidence repairs are tested on."""

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class SwingingSegment:
    """The segment turns by the rotation vector (a0 sin(t/p0), a1 cos(t/p1), a2 sin(t/p2))
    and moves ``speed`` mm a frame along x and ``sway`` sin(t/11) along y; a marker 150 mm
    from its ``hinge`` marker swings about it by ``swing`` sin(t/swing_period) rad; a last
    marker stays far off."""

    turn: tuple[float, float, float]
    periods: tuple[float, float, float]
    speed: float
    sway: float
    hinge: int
    swing: float
    swing_period: float

    def frame(self, t: int, segment: np.ndarray) -> np.ndarray:
        """``(len(segment) + 2, 3)``: the segment's markers, the swinging one, the far one."""
        (a0, a1, a2), (p0, p1, p2) = self.turn, self.periods
        turn = Rotation.from_rotvec([a0 * np.sin(t / p0), a1 * np.cos(t / p1), a2 * np.sin(t / p2)])
        moved = turn.apply(segment) + [self.speed * t, self.sway * np.sin(t / 11), 0.0]
        swinging = moved[self.hinge] + Rotation.from_rotvec([self.swing * np.sin(t / self.swing_period), 0, 0]).apply(
            [0.0, 0.0, 150.0])
        return np.vstack([moved, swinging, [900.0, 0.0, 1000.0]])
