"""The velocity of a marker seen again after a gap: the motion of its segment, not its prediction's step."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from formulations.markers.rigid import RIGID_SD_MM

# A displacement further than this many sds of a marker's motion residual (3D) from its
# neighbours' is a jump of its prediction, not a velocity: the guide's gates are 5 sds wide.
JUMP_SIGMAS = 5.0
SEGMENT_NEIGHBOURS = 3  # rigid neighbours seen twice that fix a segment's motion (a rotation needs three)


class RejoiningMarkers(Protocol):
    """What the rule reads of a ``MarkerState`` (a protocol: the state imports this module)."""

    @property
    def position(self) -> np.ndarray: ...
    @property
    def neighbours(self) -> np.ndarray: ...
    @property
    def distance_var(self) -> np.ndarray: ...
    @property
    def step_var(self) -> np.ndarray: ...
    def neighbour_motion(
        self, rows: np.ndarray, usable: np.ndarray, source: np.ndarray, target: np.ndarray, motion_var: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...


def rejoined_velocity(
    state: RejoiningMarkers, velocity: np.ndarray, back: np.ndarray, measured: np.ndarray, now: np.ndarray,
) -> np.ndarray:
    """``velocity`` with each marker seen again after a gap (``back``) at ``now`` moved by
    the rigid motion of its neighbours seen in this frame and the one before (``measured``;
    ``MarkerState.neighbour_motion``: rigid near ones first, a translation with fewer than three).

    The displacement from where the gap left it to where it is predicted now is no velocity:
    the prediction jumps whenever the neighbours it follows change, and a jump taken as a
    velocity puts the next gate off the marker: lost and found every other frame (CMU 135_02's
    right forearm, 40 frames). So a displacement more than ``JUMP_SIGMAS`` sds of the marker's
    motion off its neighbours' is replaced by theirs. Where ``SEGMENT_NEIGHBOURS`` or more of
    those neighbours share its segment (learned distance sd under ``RIGID_SD_MM``) their motion
    replaces a small jump too: a returning marker's velocity steers the neighbours still unseen
    that follow it (Vicon's STERr, back 13 mm off, within 5 sd, put STER 25 mm off, on STERl's
    point), and the segment's motion is the better estimate (nearer the true velocity on 81-89 %
    of returns, RMS 1.4-8 times lower, on six cells of the accuracy matrix from 0 to 4 mm of noise).
    With no neighbour seen twice the velocity stays.
    """
    rows = np.flatnonzero(back & measured[state.neighbours].any(axis=1))
    if not len(rows):
        return velocity
    around = state.neighbours[rows]
    usable = measured[around]
    rotation, c_s, c_t, _ = state.neighbour_motion(rows, usable, state.position[around], now[around], state.step_var[rows])
    shared = now[rows] - (np.einsum("sji,sj->si", rotation, now[rows] - c_t) + c_s)
    jump = np.linalg.norm(velocity[rows] - shared, axis=1) > JUMP_SIGMAS * np.sqrt(3 * state.step_var[rows])
    jump |= (usable & (state.distance_var[rows] < RIGID_SD_MM**2)).sum(axis=1) >= SEGMENT_NEIGHBOURS
    rejoined = velocity.copy()
    rejoined[rows[jump]] = shared[jump]
    return rejoined
