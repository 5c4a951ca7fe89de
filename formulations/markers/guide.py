"""A frame-by-frame nearest-neighbour track that centres the gates of a window.

Each frame: predict every marker (``MarkerState.predict``), assign points to markers
by ``linear_sum_assignment`` on distance with a constant miss cost, and advance the
state. The miss cost does not grow with the gate: after an occlusion the prediction
from neighbouring markers is better than a far point, and a wrong pick here would
move the gates of every later frame. This is the "standard tracking technique" of Ringer & Lasenby; here
it only decides *where to look*. The window LP decides *what to take*.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from formulations.markers.cluster_search import search_lost_clusters
from formulations.markers.first_step import coherent_steps, first_velocities
from formulations.markers.reacquire import REACQUISITION, Reacquisition, realign_lost, refine_by_segment
from formulations.markers.shape_reacquire import reacquire_by_shape
from formulations.markers.state import MarkerState


@dataclass(frozen=True)
class Gate:
    """Gate radius around a marker's prediction.

    Attributes:
        radius_mm: Smallest radius.
        growth_mm: Added per frame unseen to the gate of a stranded marker.
        max_radius_mm: Largest radius.
        unknown_velocity_radius_mm: Radius while a marker's velocity is unknown (just
            after the labeled first frame): it must cover one frame of fast motion.
        motion_sigmas: Gate half-width in sds of the marker's motion residual (3D).
        first_step_reach_mm: Longest first step looked for after a labeled frame
            (``first_step``): twice the unknown-velocity gate.
    """

    radius_mm: float = 60.0
    growth_mm: float = 20.0
    max_radius_mm: float = 400.0
    unknown_velocity_radius_mm: float = 100.0
    motion_sigmas: float = 5.0
    first_step_reach_mm: float = 200.0

    def miss_cost(self, state: MarkerState) -> np.ndarray:
        """``(N,)`` cost of leaving a marker without a point in the nearest-neighbour track.

        ``radius_mm`` for a marker unseen last frame (after an occlusion the prediction from
        its neighbours beats a far point, and a wrong pick here moves every later gate); a
        marker seen last frame may move as far as its own motion says
        (``motion_sigmas`` sd of its learned residual): a fast limb must not be dropped.
        """
        own = self.motion_sigmas * np.sqrt(3 * state.step_var)
        miss: np.ndarray = np.where(state.visible & state.velocity_known, np.maximum(own, self.radius_mm), self.radius_mm)
        return miss

    def radius(self, state: MarkerState) -> np.ndarray:
        """``motion_sigmas`` sd (3D) of the marker's learned prediction error
        (``MarkerState.prediction_var``), between ``radius_mm`` and ``max_radius_mm``: a
        marker on a fast limb, or in a take at a low frame rate, keeps its points inside its
        gate, and one occluded for long looks only as far as its prediction can have drifted
        (a gate grown by a fixed step per frame took in so many points that every marker of
        a window became one coupled component)."""
        motion = self.motion_sigmas * np.sqrt(3 * state.prediction_var(state.unseen))
        grown = np.maximum(self.radius_mm, np.minimum(motion, self.max_radius_mm))
        # Nothing carries a stranded marker (no seen neighbour to follow): its drift was
        # never learned, so its gate grows by a fixed step instead.
        blind = np.minimum(self.radius_mm + self.growth_mm * state.unseen, self.max_radius_mm)
        grown = np.where(state.stranded(1), np.maximum(grown, blind), grown)
        radius: np.ndarray = np.where(state.velocity_known, grown, np.maximum(grown, self.unknown_velocity_radius_mm))
        return radius


@dataclass(frozen=True)
class GuideTrack:
    """Per frame 1..M: prediction, gate radius and velocity before the frame, tracking state."""

    predicted: np.ndarray  # (M, N, 3)
    radius: np.ndarray  # (M, N)
    velocity: np.ndarray  # (M, N, 3) displacement per frame expected into frame m; NaN if unknown
    tracked: np.ndarray  # (M, N) seen in the frames before m, long enough to trust its prediction
    unseen: np.ndarray  # (M, N) frames unseen before m (0: seen in frame m-1)
    burst_var: np.ndarray  # (M, N) the guide's burst variance before frame m (``MarkerState.burst_var``)
    point: np.ndarray | None = None  # (M, N) the point it took in frame m, -1 none
    carriers: np.ndarray | None = None  # (M, N, K) ``MarkerState.carriers`` before frame m
    # The states it advanced through: held here while the window is solved, so that the
    # labels' advances with the same points reuse them (``MarkerState.advance`` keeps its
    # advanced states only weakly).
    states: tuple[MarkerState, ...] = ()

    def continued(self, f: int, n_points: int) -> np.ndarray:
        """``(K,)`` the points of window frame f (1..M) the guide gave a marker seen the frame
        before: the ends of tracks, not something appearing. None known without ``point``."""
        held = np.zeros(n_points, bool)
        if self.point is not None:
            on = (self.point[f - 1] >= 0) & (self.unseen[f - 1] == 0)
            held[self.point[f - 1][on]] = True
        return held


def guide_track(
    state: MarkerState, frames: list[np.ndarray], gate: Gate = Gate(), trust_after: int = 3,
    reacquisition: Reacquisition = REACQUISITION,
) -> GuideTrack:
    """Run the nearest-neighbour tracker over ``frames`` from ``state``.

    A marker counts as tracked once seen ``trust_after`` frames in a row: a marker just
    re-acquired may have been re-acquired wrongly, and others should not lean on it.
    Markers lost together are looked for where their group registers to the cloud
    (``realign_lost``), and each rigid cluster of them by its own shape, whatever pose it
    comes back in (``search_lost_clusters``).
    """
    m, n = len(frames), len(state.position)
    predicted, velocity = np.empty((m, n, 3)), np.empty((m, n, 3))
    radius, tracked = np.empty((m, n)), np.empty((m, n), bool)
    unseen = np.empty((m, n), dtype=int)
    burst_var = np.empty((m, n))
    point = np.full((m, n), -1)
    carriers = np.zeros((m,) + state.neighbours.shape, bool)
    states: list[MarkerState] = []
    state = _moving_start(state, frames, gate)
    for f, points in enumerate(frames):
        lost = state.stranded(reacquisition.lost_after)
        guess = state.predict()
        if lost.any():
            guess = realign_lost(guess, lost, state.visible, points, reacquisition)
            guess = search_lost_clusters(guess, state, lost, points)
            guess = refine_by_segment(guess, lost, state.neighbours, state.distance_var, points, reacquisition)
        guess = reacquire_by_shape(guess, state, points)
        carriers[f] = state.carriers
        predicted[f], tracked[f], unseen[f], burst_var[f] = guess, state.streak >= trust_after, state.unseen, state.burst_var
        # Predicted displacement: a marker's own velocity while seen, its neighbours'
        # motion while occluded; unknown only right after the labeled first frame.
        unknown = state.visible & ~state.velocity_known
        velocity[f] = np.where(unknown[:, None], np.nan, predicted[f] - state.position)
        radius[f] = gate.radius(state)
        miss = gate.miss_cost(state)
        assigned = assign_nearest(predicted[f], points, radius[f], miss)
        shared = shared_motion(state, predicted[f], points, assigned)
        if shared is not None:
            predicted[f] += shared
            velocity[f] += shared
            assigned = assign_nearest(predicted[f], points, radius[f], miss)
        seen, point[f] = assigned >= 0, assigned
        taken = np.zeros((n, 3))
        taken[seen] = points[assigned[seen]]
        state = state.advance(taken, seen)
        states.append(state)
    return GuideTrack(
        predicted=predicted, radius=radius, velocity=velocity, tracked=tracked, unseen=unseen, burst_var=burst_var,
        point=point, carriers=carriers, states=tuple(states),
    )


def _moving_start(state: MarkerState, frames: list[np.ndarray], gate: Gate) -> MarkerState:
    """The state with each seen marker of unknown velocity given its minimum-acceleration
    first step (``first_step``) as velocity (still unknown: its gate stays wide), when most
    seen markers are such (a labeled start, not one re-acquired marker)."""
    unknown = state.visible & ~state.velocity_known
    if len(frames) < 2 or unknown.sum() < max(3, state.visible.sum() // 2):
        return state
    start = state.position[unknown]
    velocity = coherent_steps(start, first_velocities(start, frames[0], frames[1], gate.first_step_reach_mm))
    moved = state.velocity.copy()
    moved[unknown] = velocity
    return replace(state, velocity=moved)


def shared_motion(state: MarkerState, predicted: np.ndarray, points: np.ndarray, assigned: np.ndarray) -> np.ndarray | None:
    """``(N, 3)`` the acceleration each marker shares with its rigid neighbours this frame.

    A limb that speeds up moves all its markers off their constant-velocity predictions
    together; the weighted mean offset of a marker's neighbours that found a point
    (weights 1 / (var + 1), rigid neighbours first) is added to its prediction before a
    second assignment. None when no marker found a point.
    """
    found = assigned >= 0
    if not found.any():
        return None
    offset = np.zeros_like(predicted)
    offset[found] = points[assigned[found]] - predicted[found]
    weight = found[state.neighbours] / (state.distance_var + 1.0)
    total = weight.sum(axis=1)
    shared: np.ndarray = np.einsum("nk,nkd->nd", weight, offset[state.neighbours]) / np.maximum(total, 1e-12)[:, None]
    return np.where((total > 0)[:, None], shared, 0.0)


def assign_nearest(
    predicted: np.ndarray, points: np.ndarray, radius: np.ndarray, miss_cost: float | np.ndarray
) -> np.ndarray:
    """Optimal one-to-one assignment of points to predictions within each gate.

    Returns:
        ``(N,)`` point index per marker, -1 for a miss.
    """
    if len(points) == 0:
        return np.full(len(predicted), -1)
    return assign_within_gates(cdist(predicted, points), radius, miss_cost)


def assign_within_gates(distance: np.ndarray, radius: np.ndarray, miss_cost: float | np.ndarray) -> np.ndarray:
    """min sum of distances over one-to-one assignments, a marker taking only what lies
    inside its gate, with a miss of cost ``miss_cost`` allowed for every marker.

    Args:
        distance: ``(N, D)`` distance from each marker's prediction to each detection.
        radius: ``(N,)`` gate radius of each marker.
        miss_cost: Cost of leaving a marker unassigned, one for all or ``(N,)``.

    Returns:
        ``(N,)`` detection index per marker, -1 for a miss.
    """
    n, d = distance.shape
    blocked = 1e9
    # [gated distances | misses on the diagonal] written in place: stacking two blocks cost
    # as much as the assignment, twice a frame
    cost = np.full((n, d + n), blocked)
    np.copyto(cost[:, :d], distance, where=distance <= radius[:, None])
    cost.ravel()[d :: d + n + 1] = miss_cost
    rows, cols = linear_sum_assignment(cost)
    result = np.full(n, -1)
    hit = cols < d
    result[rows[hit]] = cols[hit]
    return result
