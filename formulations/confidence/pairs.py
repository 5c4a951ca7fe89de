"""Min-marginals of two objects moved together, the others held on their chosen paths.

For a pair (a, b) the joint network has states (i, j) = (slot of a, slot of b) per frame,
steps

    c_f((i, j), (i', j')) = A_f(i, i') + B_f(j, j') + J_f(i, j, i', j')

(A, B each object's own steps, layout terms with the fixed others included; J the layout
term between a and b, absent when they are no layout pair), and ``allowed`` states: both
slots usable with the others fixed, and not holding one resource together. Its forward and
backward distances give, as for one object (``single``), the cheapest pair of paths
through every joint state. Without J a step separates: min over i, then over j, K^3 work
per frame instead of K^4. All pairs advance together, one frame at a time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def pair_min_marginals(
    a: NDArray[np.float64], b: NDArray[np.float64], allowed: NDArray[np.bool_], joint: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """``(P, M, K, K)`` cheapest joint paths through each state of frames 1..M.

    Args:
        a, b: ``(P, M + 1, K, K)`` step costs of each pair's first and second object.
        allowed: ``(P, M + 2, K, K)`` joint states the paths may use.
        joint: ``(P, M + 1, K, K, K, K)`` the steps' term in both objects (J), or None.
    """
    pairs, steps, width, _ = a.shape
    alpha = np.full((pairs, steps + 1, width, width), np.inf)
    beta = np.full((pairs, steps + 1, width, width), np.inf)
    alpha[:, 0, 0, 0] = 0.0
    beta[:, steps, 0, 0] = 0.0
    for f in range(steps):
        reached = _forward(alpha[:, f], a[:, f], b[:, f], None if joint is None else joint[:, f])
        alpha[:, f + 1] = np.where(allowed[:, f + 1], reached, np.inf)
    for f in range(steps - 1, -1, -1):
        onward = _backward(beta[:, f + 1], a[:, f], b[:, f], None if joint is None else joint[:, f])
        beta[:, f] = np.where(allowed[:, f], onward, np.inf)
    marginal: NDArray[np.float64] = (alpha + beta)[:, 1:-1]
    return marginal


def _forward(
    alpha: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64], joint: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """min over (i, j) of alpha(i, j) + A(i, i') + B(j, j') [+ J(i, j, i', j')], as (P, i', j')."""
    if joint is not None:
        total = alpha[:, :, :, None, None] + a[:, :, None, :, None] + b[:, None, :, None, :] + joint
        full: NDArray[np.float64] = total.min(axis=(1, 2))
        return full
    over_j = (alpha[:, :, :, None] + b[:, None, :, :]).min(axis=2)  # (P, i, j')
    separable: NDArray[np.float64] = (over_j[:, :, None, :] + a[:, :, :, None]).min(axis=1)  # (P, i', j')
    return separable


def _backward(
    beta: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64], joint: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """min over (i', j') of A(i, i') + B(j, j') [+ J] + beta(i', j'), as (P, i, j)."""
    if joint is not None:
        total = beta[:, None, None, :, :] + a[:, :, None, :, None] + b[:, None, :, None, :] + joint
        full: NDArray[np.float64] = total.min(axis=(3, 4))
        return full
    over_j = (b[:, None, :, :] + beta[:, :, None, :]).min(axis=3)  # (P, i', j)
    separable: NDArray[np.float64] = (a[:, :, :, None] + over_j[:, None, :, :]).min(axis=2)  # (P, i, j)
    return separable
