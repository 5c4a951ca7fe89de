"""Weighted rigid alignment (Kabsch), batched over many small point sets."""

from __future__ import annotations

import numpy as np

RIGID_SD_MM = 10.0  # as ShapeReacquisition.max_sd_mm: one segment's skin markers keep their distances


def rigid_transform(source: np.ndarray, target: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotation R and centroids such that ``target ~ R (source - c_s) + c_t`` for each set.

    Minimises sum_k w_k || R (a_k - c_s) + c_t - b_k ||^2 by the SVD of the weighted
    cross-covariance H = sum_k w_k (a_k - c_s)(b_k - c_t)^T: R = V diag(1, 1, det(V U^T)) U^T.

    Args:
        source, target: ``(S, K, 3)`` point sets.
        weight: ``(S, K)`` non-negative weights; each set needs a positive total.

    Returns:
        ``(S, 3, 3)`` rotations, ``(S, 3)`` source and ``(S, 3)`` target centroids.
    """
    # Stacked matmuls rather than einsum: a call fits a few sets of ~16 points, so numpy's
    # per-call overhead is the cost, and einsum's is the larger.
    w = weight / np.maximum(weight.sum(axis=1, keepdims=True), 1e-12)
    c_s = np.matmul(w[:, None], source)[:, 0]
    c_t = np.matmul(w[:, None], target)[:, 0]
    h = np.matmul((source - c_s[:, None]).transpose(0, 2, 1), w[..., None] * (target - c_t[:, None]))
    u, _, vt = np.linalg.svd(h)
    sign = np.sign(np.linalg.det(np.matmul(vt, u)))  # det(V U^T) = det(V) det(U) = det(V^T U^T)
    vt[:, 2] *= np.where(sign == 0, 1.0, sign)[:, None]  # diag(1, 1, sign) V^T
    rotation = np.matmul(u, vt).transpose(0, 2, 1)  # (U diag(1, 1, sign) V^T)^T = V diag(1, 1, sign) U^T
    return rotation, c_s, c_t


MIN_SPAN_MM = 10.0  # RMS spread across the best-fit line below which a rotation is left free


def span_across_line(points: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """``(S,)`` weighted RMS distance (mm) of each set's ``(S, K, 3)`` points from their best-fit
    line: near 0, the points fix no rotation about that line, and a fit turns a point far from
    it at random."""
    w = weight / np.maximum(weight.sum(axis=1, keepdims=True), 1e-12)
    centred = points - np.einsum("sk,skd->sd", w, points)[:, None]
    scatter = np.einsum("sk,ski,skj->sij", w, centred, centred)
    span: np.ndarray = np.sqrt(np.maximum(np.linalg.eigvalsh(scatter)[:, 1], 0.0))
    return span


def line_motion(source: np.ndarray, target: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The least turn R taking each ``(S, K, 3)`` source set's weighted best-fit line onto its
    target's, with the weighted centroids, as ``rigid_transform`` returns them: points on a
    line fix its direction but no turn about it, and this turns about no axis it need not.

    With unit line directions a (source) and b (target, signed so the points keep their
    order along it), v = a x b and c = a . b: R = I + [v]x + [v]x^2 / (1 + c) (Rodrigues).
    """
    w = weight / np.maximum(weight.sum(axis=1, keepdims=True), 1e-12)
    c_s = np.einsum("sk,skd->sd", w, source)
    c_t = np.einsum("sk,skd->sd", w, target)
    a, along_a = _direction(source - c_s[:, None], w)
    b, along_b = _direction(target - c_t[:, None], w)
    b *= np.where(np.einsum("sk,sk->s", w, along_a * along_b) < 0, -1.0, 1.0)[:, None]
    v, c = np.cross(a, b), np.einsum("sd,sd->s", a, b)
    cross = np.zeros((len(a), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    cross -= cross.transpose(0, 2, 1)
    rotation = np.eye(3) + cross + cross @ cross / np.maximum(1.0 + c, 1e-9)[:, None, None]
    return rotation, c_s, c_t


def _direction(centred: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each set's principal direction ``(S, 3)`` and its points' positions along it ``(S, K)``."""
    scatter = np.einsum("sk,ski,skj->sij", w, centred, centred)
    direction = np.linalg.eigh(scatter)[1][:, :, 2]
    return direction, np.einsum("skd,sd->sk", centred, direction)


FOLLOW_ITERATIONS = 3
FIRM_INLIERS = 3


def follow_neighbours(
    source: np.ndarray, target: np.ndarray, prior: np.ndarray, motion_var: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rigid motion of the neighbours that really move with an occluded marker.

    A weighted fit over every neighbour averages segments that move differently (a still
    thigh and a lifting forearm around a lost wrist). Iteratively reweighted least squares
    with Cauchy weights w_k = p_k / (1 + (e_k / c)^2), e_k the neighbour's residual under
    the current fit, drops the neighbours that do not share the motion; c is 3 sd of the
    marker's own motion residual (``MarkerState.motion_var``), so it scales with the take.
    The first fit is the prior-weighted one: the prior favours near, rigid neighbours.

    Returns:
        Rotations and centroids as ``rigid_transform``, and ``(S, K)`` the usable neighbours
        within c of the fit: three or more make it firm (``FIRM_INLIERS``), a rigid body that
        really carries the marker; the rest did not share its motion.

    Args:
        source, target: ``(S, K, 3)`` neighbours at the anchor frame and now.
        prior: ``(S, K)`` prior weights (0 for unusable neighbours).
        motion_var: ``(S,)`` per-axis motion residual variance of each marker (mm^2).
    """
    scale2 = 9.0 * 3.0 * motion_var[:, None]
    weight = prior
    for _ in range(FOLLOW_ITERATIONS):
        rotation, c_s, c_t = rigid_transform(source, target, weight)
        moved = np.matmul(source - c_s[:, None], rotation.transpose(0, 2, 1)) + c_t[:, None]
        error2 = ((moved - target) ** 2).sum(axis=2)
        weight = prior / (1.0 + error2 / scale2)
    rotation, c_s, c_t = rigid_transform(source, target, weight)
    moved = np.matmul(source - c_s[:, None], rotation.transpose(0, 2, 1)) + c_t[:, None]
    inliers: np.ndarray = (prior > 0) & (((moved - target) ** 2).sum(axis=2) <= scale2)
    return rotation, c_s, c_t, inliers
