"""Where to look for markers lost together: their stale predictions aligned to the cloud.

A marker whose neighbours are seen follows their rigid motion (``MarkerState.predict``).
When a whole group is lost (the subject left the volume, or a body part was hidden for
a while) nothing carries it: its prediction is a damped constant velocity that lags the
subject by the distance walked meanwhile, and nearest-point assignment on re-entry then
hands each marker the point of the one ahead of it. The group's shape is still known, so
it is registered to the free points by trimmed ICP: from the start translations t_0 = 0
and t_0 = mean(free points) - mean(lost predictions), repeat

    j(n)   = nearest free point to R p_n + t,
    (R, t) = argmin sum_{n: ||R p_n + t - x_j(n)|| <= r} ||R p_n + t - x_j(n)||^2   (Kabsch),

and keep the start whose alignment brings most lost markers within ``inlier_mm`` of a
point. Only an alignment with at least ``min_inliers`` such markers, and a fraction
``min_share`` of the markers it could explain, moves the predictions: a few ghosts must
not drag a lost subject anywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from formulations.markers.rigid import rigid_transform


@dataclass(frozen=True)
class Reacquisition:
    """When and how lost markers are registered to the cloud.

    Attributes:
        lost_after: Frames unseen, with no seen neighbour to follow, before a marker counts as lost.
        claim_mm: Points this close to a seen marker's prediction are its, not the lost group's.
        trim_mm: r, matches farther than this after the first iteration do not pull the fit.
        inlier_mm: A lost marker within this of a point after alignment is explained by it.
        min_inliers, min_share: How much of the group must be explained to trust the alignment.
        iterations: ICP iterations per start.
    """

    lost_after: int = 3
    claim_mm: float = 30.0
    trim_mm: float = 60.0
    inlier_mm: float = 40.0
    min_inliers: int = 4
    min_share: float = 0.5
    iterations: int = 15


REACQUISITION = Reacquisition()


def realign_lost(
    predicted: np.ndarray, lost: np.ndarray, seen: np.ndarray, points: np.ndarray,
    settings: Reacquisition = Reacquisition(),
) -> np.ndarray:
    """``(N, 3)`` predictions with the lost markers' moved by the group's registration.

    Args:
        predicted: ``(N, 3)`` predictions for this frame.
        lost: ``(N,)`` markers lost together (see ``Reacquisition.lost_after``).
        seen: ``(N,)`` markers whose predictions are trusted (seen last frame).
        points: ``(P, 3)`` this frame's points.
    """
    source = predicted[lost]
    free = free_points(points, predicted[seen], settings.claim_mm)
    if len(source) < settings.min_inliers or len(free) < settings.min_inliers:
        return predicted
    tree = cKDTree(free)
    starts = (np.zeros(3), free.mean(axis=0) - source.mean(axis=0))
    fits = [_icp(source, tree, free, start, settings) for start in starts]
    inliers, moved = max(fits, key=lambda fit: fit[0])
    if inliers < max(settings.min_inliers, settings.min_share * min(len(source), len(free))):
        return predicted
    realigned = predicted.copy()
    realigned[lost] = moved
    return realigned


def refine_by_segment(
    guess: np.ndarray, lost: np.ndarray, neighbours: np.ndarray, distance_var: np.ndarray, points: np.ndarray,
    settings: Reacquisition = Reacquisition(),
) -> np.ndarray:
    """Each lost marker moved by the trimmed ICP of its own neighbourhood, from ``guess``.

    A body is rigid only by segment: once the group is registered, a lost marker's
    neighbourhood (itself and its K neighbours, weighted 1 / (var + 1) as the state
    weighs them, itself as its most rigid neighbour) is registered again on its own,
    which follows a limb that swung while the subject was away.
    """
    index = np.flatnonzero(lost)
    # A neighbourhood of fewer than three markers (a take of one or two) fixes no rotation.
    if len(index) == 0 or len(points) < 3 or neighbours.shape[1] < 2:
        return guess
    rigidity = 1.0 / (distance_var[index] + 1.0)
    weight = np.column_stack([rigidity.max(axis=1), rigidity])  # (L, K + 1)
    source = guess[np.column_stack([index, neighbours[index]])]  # (L, K + 1, 3)
    tree, moved = cKDTree(points), source
    for _ in range(settings.iterations):
        distance, nearest = tree.query(moved)
        pull = weight * (distance <= settings.trim_mm)
        fit = (pull > 0).sum(axis=1) >= 3
        if not fit.any():
            break
        rotation, c_s, c_t = rigid_transform(source[fit], points[nearest[fit]], pull[fit])
        moved = moved.copy()
        moved[fit] = np.einsum("sij,skj->ski", rotation, source[fit] - c_s[:, None]) + c_t[:, None]
    refined = guess.copy()
    refined[index] = moved[:, 0]
    return refined


def _icp(
    source: np.ndarray, tree: cKDTree, free: np.ndarray, start: np.ndarray, settings: Reacquisition,
) -> tuple[int, np.ndarray]:
    """Trimmed ICP from translation ``start``: (markers within ``inlier_mm``, moved source)."""
    moved = source + start
    for iteration in range(settings.iterations):
        distance, nearest = tree.query(moved)
        # The first step takes every match: the start may be off by more than r.
        keep = distance <= (np.inf if iteration == 0 else settings.trim_mm)
        if keep.sum() < 3:
            break
        rotation, c_s, c_t = rigid_transform(source[keep][None], free[nearest[keep]][None], np.ones((1, keep.sum())))
        moved = (source - c_s[0]) @ rotation[0].T + c_t[0]
    distance, _ = tree.query(moved)
    return int((distance <= settings.inlier_mm).sum()), moved


def free_points(points: np.ndarray, trusted: np.ndarray, claim_mm: float) -> np.ndarray:
    """The points no trusted prediction lies within ``claim_mm`` of."""
    if len(trusted) == 0 or len(points) == 0:
        return points
    # every distance at once: a search tree built for one query per frame costs three times as much
    free: np.ndarray = points[cdist(points, trusted).min(axis=1) > claim_mm]
    return free
