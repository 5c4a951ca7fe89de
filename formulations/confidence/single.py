"""Min-marginals of each object's own network: the cheapest path through every slot.

For one layered network with step costs c_f(i, j) (``layers``), forward and backward
distances

    alpha_0 = [0 at the source],   alpha_{f+1}(j) = min_i alpha_f(i) + c_f(i, j),
    beta_{M+1} = [0 at the sink],  beta_f(i)      = min_j c_f(i, j) + beta_{f+1}(j),

give the min-marginal m_f(u) = alpha_f(u) + beta_f(u): the cost of the cheapest
source-to-sink path through slot u of frame f. Slots that are not ``allowed`` are left out
(distance inf). The backward distances are the forward ones of the reversed network
(frames in reverse order, c_f transposed), so both directions, every object and every
set of allowed slots advance together, one frame at a time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.layers import Layers


def min_marginals(grid: Layers, step: NDArray[np.float64], allowed: NDArray[np.bool_]) -> NDArray[np.float64]:
    """``(..., N, M, K)`` cheapest path cost through each slot of frames 1..M.

    Run batch by batch of ``grid`` (objects of similar widest block, ``layers``).

    Args:
        grid: The window's layers.
        step: Step costs laid out as ``grid.step`` (inf where no arc).
        allowed: ``(..., N, M + 2, K)`` slots a path may use (only nodes); leading axes give
            other sets of allowed slots in the same networks.
    """
    marginal = np.full(allowed.shape[:-2] + (allowed.shape[-2] - 2, allowed.shape[-1]), np.inf)
    for objects in grid.batches:
        w = int(grid.span[objects[0]])
        marginal[..., objects, :, :w] = _through(grid.batch(step, objects), allowed[..., objects, :, :w])
    return marginal


def _through(step: NDArray[np.float64], allowed: NDArray[np.bool_]) -> NDArray[np.float64]:
    """``min_marginals`` of objects of one width."""
    steps = step.shape[1]
    arcs = np.stack([step, step[:, ::-1].swapaxes(2, 3)])  # forward, then the reversed network
    arcs = arcs.reshape((2,) + (1,) * (allowed.ndim - 3) + step.shape)
    usable = np.stack([allowed, allowed[..., ::-1, :]])
    distance = np.full(usable.shape, np.inf)  # alpha, then beta with frames reversed
    distance[..., 0, 0] = 0.0
    for f in range(steps):
        reached = (distance[..., f, :, None] + arcs[..., f, :, :]).min(axis=-2)
        distance[..., f + 1, :] = np.where(usable[..., f + 1, :], reached, np.inf)
    marginal: NDArray[np.float64] = (distance[0] + distance[1, ..., ::-1, :])[..., 1:-1, :]
    return marginal
