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

At 70-90 mm a frame a glove of three markers 43 mm apart that turns as it travels has no
clear least acceleration: its hand accelerates by as much as its markers are apart, and a
marker sent onto a glove mate's point, the mate left without one, can cost less in sum (the
wheelchair racing take under the matrix's default scenario, seed 0: the glove's second and
third markers exchanged from frame 1 to the end, 900 wrong labels). What does tell them apart
is that a limb carries its markers together: so the matching is made again, ``SHARED_ROUNDS``
times, with each step also paying its departure from the median step its ``NEIGHBOURS``
nearest markers took in the matching before,

    c_ij = a_ij + |(x_j - p_i) - median_{k near i} v_k|     (mm, as a_ij),

and the miss priced again from the markers' least c_ij. Both terms are motion the shared
translation does not explain, so they add as they are.

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
SHARED_ROUNDS = 2  # matchings with the shared step re-estimated from the one before


def miss_cost(least: np.ndarray) -> float:
    """A marker left without a point: ``MISS_FACTOR`` times the median of the markers'
    least accelerations ``least`` (inf where a marker reaches no point); at least 1 mm."""
    return MISS_FACTOR * max(float(np.median(least[np.isfinite(least)])), 1.0 / MISS_FACTOR)


def first_velocities(position: np.ndarray, following: np.ndarray, after: np.ndarray, reach_mm: float) -> np.ndarray:
    """``(K, 3)`` velocity of each marker by minimum acceleration, then by acceleration plus
    departure from the neighbours' shared step (module doc); 0 for one left without a point.

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
    if not np.isfinite(cost.min(axis=1)).any():
        return velocity
    took = _matched(cost)
    if k > NEIGHBOURS:
        _, nearest = cKDTree(position).query(position, NEIGHBOURS + 1)
        for _ in range(SHARED_ROUNDS):
            shared = _shared_step(np.where(took[:, None] >= 0, step[np.arange(k), took], np.nan), nearest[:, 1:])
            departure = np.nan_to_num(np.linalg.norm(step - shared[:, None], axis=2), nan=0.0)
            took = _matched(cost + departure)
    velocity[took >= 0] = step[np.flatnonzero(took >= 0), took[took >= 0]]
    return velocity


def _matched(cost: np.ndarray) -> np.ndarray:
    """``(K,)`` the point each marker takes (-1 none): one to one, least ``cost`` ``(K, P)``, a
    miss at ``miss_cost`` of the markers' least costs."""
    k, p = cost.shape
    miss = np.full((k, k), np.inf)
    np.fill_diagonal(miss, miss_cost(cost.min(axis=1)))
    rows, cols = linear_sum_assignment(np.hstack([np.minimum(cost, 1e9), np.minimum(miss, 1e9)]))
    took = np.full(k, -1)
    took[rows[cols < p]] = cols[cols < p]
    return took


def _shared_step(steps: np.ndarray, nearest: np.ndarray) -> np.ndarray:
    """``(K, 3)`` the median of each marker's nearest markers' steps (NaN rows: no step), NaN
    where none of them has one."""
    around = steps[nearest]  # (K, NEIGHBOURS, 3)
    shared = np.full((len(steps), 3), np.nan)
    some = np.isfinite(around[..., 0]).any(axis=1)
    shared[some] = np.nanmedian(around[some], axis=1)
    return shared


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
