"""Weighted rigid alignment (Kabsch), batched over many small point sets."""

from __future__ import annotations

import numpy as np


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
    total = weight.sum(axis=1, keepdims=True)
    w = weight / np.maximum(total, 1e-12)
    c_s = np.einsum("sk,skd->sd", w, source)
    c_t = np.einsum("sk,skd->sd", w, target)
    h = np.einsum("sk,ski,skj->sij", w, source - c_s[:, None], target - c_t[:, None])
    u, _, vt = np.linalg.svd(h)
    sign = np.sign(np.linalg.det(np.einsum("sji,skj->sik", vt, u)))  # det(V U^T)
    fix = np.ones((len(h), 3))
    fix[:, 2] = np.where(sign == 0, 1.0, sign)
    rotation = np.einsum("sji,sj,skj->sik", vt, fix, u)  # V diag(fix) U^T
    return rotation, c_s, c_t
