"""Min-marginals of two objects moved together, the others held on their chosen paths.

For a pair (a, b) the joint network has states (i, j) = (slot of a, slot of b) per frame,
steps

    c_f((i, j), (i', j')) = A_f(i, i') + B_f(j, j') + J_f(i, j, i', j')

(A, B each object's own steps, layout terms with the fixed others included; J the layout
term between a and b, absent when they are no layout pair), and ``allowed`` states: both
slots usable with the others fixed, and not holding one resource together. Its forward and
backward distances give, as for one object (``single``), the cheapest pair of paths
through every joint state. Without J a step separates: min over j, then over i, K^3 work
per frame instead of K^4. The backward distances are the forward ones of the reversed
network (frames in reverse, A, B and J with their ends swapped), so both directions and
all pairs advance together, one frame at a time.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

Kind = TypeVar("Kind", np.float64, np.bool_)


def pair_min_marginals(
    a: NDArray[np.float64], b: NDArray[np.float64], allowed: NDArray[np.bool_], joint: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """``(P, M, K, K)`` cheapest joint paths through each state of frames 1..M.

    Args:
        a, b: ``(P, M + 1, K, K)`` step costs of each pair's first and second object.
        allowed: ``(P, M + 2, K, K)`` joint states the paths may use.
        joint: ``(P, M + 1, K, K, K, K)`` the steps' term in both objects (J), or None.
    """
    steps = a.shape[1]
    first, second = _both_ways(a, 3), _both_ways(b, 3)
    both = None if joint is None else _both_ways(joint, 4, 5)
    usable = _pairs_last(np.stack([allowed, allowed[:, ::-1]]))
    distance = np.full(usable.shape, np.inf)  # (2, M + 2, K, K, P): alpha, then beta with frames reversed
    distance[:, 0, 0, 0] = 0.0
    for f in range(steps):
        reached = _forward(distance[:, f], first[:, f], second[:, f], None if both is None else both[:, f])
        distance[:, f + 1] = np.where(usable[:, f + 1], reached, np.inf)
    marginal: NDArray[np.float64] = np.moveaxis(distance[0] + distance[1, ::-1], -1, 0)[:, 1:-1]
    return marginal


def _both_ways(step: NDArray[np.float64], *heads: int) -> NDArray[np.float64]:
    """``(2, M + 1, ..., P)`` the steps, then the reversed network's: frames in reverse,
    each step's ends swapped (``heads``: the axes of the step's end, put first)."""
    tails = (axis for axis in range(2, step.ndim) if axis not in heads)
    reverse = step[:, ::-1].transpose(0, 1, *heads, *tails)
    return _pairs_last(np.stack([step, reverse]))


def _pairs_last(values: NDArray[Kind]) -> NDArray[Kind]:
    """``values`` ``(2, P, ...)`` as ``(2, ..., P)``: a min over a few slots then runs over
    whole rows of pairs, not over rows of K slots (numpy pays per row)."""
    return np.ascontiguousarray(np.moveaxis(values, 1, -1))


def _forward(
    alpha: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64], joint: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """min over (i, j) of alpha(i, j) + A(i, i') + B(j, j') [+ J(i, j, i', j')], as (2, i', j', P)."""
    if joint is not None:
        total = alpha[:, :, :, None, None] + a[:, :, None, :, None] + b[:, None, :, None, :] + joint
        full: NDArray[np.float64] = total.min(axis=(1, 2))
        return full
    over_j = (alpha[:, :, :, None] + b[:, None, :, :]).min(axis=2)  # (2, i, j', P)
    separable: NDArray[np.float64] = (over_j[:, :, None, :] + a[:, :, :, None]).min(axis=1)  # (2, i', j', P)
    return separable
