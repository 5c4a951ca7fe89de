"""Min-marginals of each object's own network: the cheapest path through every slot.

For one layered network with step costs c_f(i, j) (``layers``), forward and backward
distances

    alpha_0 = [0 at the source],   alpha_{f+1}(j) = min_i alpha_f(i) + c_f(i, j),
    beta_{M+1} = [0 at the sink],  beta_f(i)      = min_j c_f(i, j) + beta_{f+1}(j),

give the min-marginal m_f(u) = alpha_f(u) + beta_f(u): the cost of the cheapest
source-to-sink path through slot u of frame f. Slots that are not ``allowed`` are left out
(distance inf). All objects advance together, one frame at a time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def min_marginals(step: NDArray[np.float64], allowed: NDArray[np.bool_]) -> NDArray[np.float64]:
    """``(N, M, K)`` cheapest path cost through each slot of frames 1..M.

    Objects are batched by their widest block (powers of two), so that the few markers
    with a wide gate do not widen everyone's K x K steps.

    Args:
        step: ``(N, M + 1, K, K)`` step costs (inf where no arc); slots past a block's
            size have no arcs.
        allowed: ``(N, M + 2, K)`` slots a path may use.
    """
    n, steps, width, _ = step.shape
    marginal = np.full((n, steps - 1, width), np.inf)
    used = np.where(allowed.any(axis=1), np.arange(width) + 1, 0).max(axis=1)  # past the last usable slot
    bucket = np.ceil(np.log2(np.maximum(used, 1)))
    for value in np.unique(bucket):
        objects = np.flatnonzero(bucket == value)
        w = int(used[objects].max())
        marginal[objects, :, :w] = _through(step[objects, :, :w, :w], allowed[objects, :, :w])
    return marginal


def _through(step: NDArray[np.float64], allowed: NDArray[np.bool_]) -> NDArray[np.float64]:
    """``min_marginals`` of objects of one width."""
    n, steps, width, _ = step.shape
    alpha = np.full((n, steps + 1, width), np.inf)
    beta = np.full((n, steps + 1, width), np.inf)
    alpha[:, 0, 0] = 0.0
    beta[:, steps, 0] = 0.0
    for f in range(steps):
        reached = (alpha[:, f, :, None] + step[:, f]).min(axis=1)
        alpha[:, f + 1] = np.where(allowed[:, f + 1], reached, np.inf)
    for f in range(steps - 1, -1, -1):
        onward = (step[:, f] + beta[:, f + 1, None, :]).min(axis=2)
        beta[:, f] = np.where(allowed[:, f], onward, np.inf)
    marginal: NDArray[np.float64] = (alpha + beta)[:, 1:-1]
    return marginal
