"""The first step of a take: each marker's velocity when only its position is known.

A labeled first frame gives positions, not velocities, so the next frame is predicted
where each marker was, with a wide gate. That is right for a subject standing still and
wrong for one already moving: on a wheelchair racer at 70 Hz the body travels 80-95 mm a
frame while the glove markers are 30 mm apart, so within the wide gate a marker's own
point is farther than its neighbour's, and the first frame's mistakes last the take. The
window cannot tell them apart later: a cluster whose labels are passed round moves as
smoothly as the right one, only its first step is wrong.

Three frames can (minimum-acceleration linking, as in particle tracking velocimetry):
marker i at p_i taking point x_j of the next frame would be at 2 x_j - p_i in the frame
after, and its acceleration there is the distance a_ij to the nearest point of that frame.
Markers are matched to points one-to-one, minimising sum a_ij over points within
``reach_mm``; the velocity of marker i is then x_j - p_i. A marker may take none (it was
deleted in one of the two frames), at ``MISS_FACTOR`` times the subject's typical
acceleration, the median over markers of their least a_ij: a point reached only by an
acceleration far beyond the others' is a ghost or a neighbour's, and the marker is better
left where it was.

In clutter that matching is not enough: among a hundred ghosts some pair always lines up,
and a still subject's markers get random first steps larger than their true ones. A real
first step is shared: a moving limb carries its neighbouring markers together. So a step
is kept only when it agrees with the median step of the marker's ``NEIGHBOURS`` nearest
markers to within ``COHERENCE`` of the larger of the two; otherwise the marker starts
still, as it would without this module.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

MISS_FACTOR = 3.0  # a miss costs three typical accelerations
NEIGHBOURS = 3  # markers whose steps a marker's step must agree with
COHERENCE = 0.5  # largest disagreement, as a fraction of the step


def miss_cost(least: np.ndarray) -> float:
    """A marker left without a point: ``MISS_FACTOR`` times the median of the markers'
    least accelerations ``least`` (inf where a marker reaches no point); at least 1 mm."""
    return MISS_FACTOR * max(float(np.median(least[np.isfinite(least)])), 1.0 / MISS_FACTOR)


def first_velocities(position: np.ndarray, following: np.ndarray, after: np.ndarray, reach_mm: float) -> np.ndarray:
    """``(K, 3)`` velocity of each marker by minimum acceleration (module doc); 0 for one left without a point.

    Args:
        position: ``(K, 3)`` the markers at the labeled frame.
        following: ``(P, 3)`` the next frame's points.
        after: ``(Q, 3)`` the points of the frame after that.
        reach_mm: Longest first step considered.
    """
    k = len(position)
    velocity = np.zeros((k, 3))
    if len(following) == 0 or len(after) == 0:
        return velocity
    step = following[None] - position[:, None]  # (K, P, 3)
    reachable = np.linalg.norm(step, axis=2) <= reach_mm
    acceleration, _ = cKDTree(after).query(following[None] + step)  # (K, P)
    cost = np.where(reachable, acceleration, np.inf)
    least = cost.min(axis=1)
    if not np.isfinite(least).any():
        return velocity
    miss = np.full((k, k), np.inf)
    np.fill_diagonal(miss, miss_cost(least))
    rows, cols = linear_sum_assignment(np.hstack([np.minimum(cost, 1e9), np.minimum(miss, 1e9)]))
    took = cols < len(following)
    velocity[rows[took]] = step[rows[took], cols[took]]
    return velocity


def coherent_steps(position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    """``velocity`` with each step that disagrees with its neighbours' median step set to 0 (module doc).

    Marker i keeps v_i when ``|v_i - m_i| <= COHERENCE * max(|v_i|, |m_i|)``, m_i the
    median step of the ``NEIGHBOURS`` markers nearest to it at ``position``.
    """
    k = len(position)
    if k <= NEIGHBOURS:
        return np.zeros_like(velocity)
    _, nearest = cKDTree(position).query(position, NEIGHBOURS + 1)
    shared = np.median(velocity[nearest[:, 1:]], axis=1)  # column 0 is the marker itself
    disagreement = np.linalg.norm(velocity - shared, axis=1)
    scale = np.maximum(np.linalg.norm(velocity, axis=1), np.linalg.norm(shared, axis=1))
    return np.where((disagreement <= COHERENCE * scale)[:, None], velocity, 0.0)
