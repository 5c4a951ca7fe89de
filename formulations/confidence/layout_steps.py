"""The L1 layout term (``window.objective``) as step costs of one or two moving objects.

Between frames f and f + 1 (f = 1..M-1) a layout pair (a, b) costs

    mu_ab || (r_a,f+1 - r_b,f+1) - (r_a,f - r_b,f) ||_1.

With b held on its chosen path this is a step cost of a alone, ``partner_steps``; with
both moving it is a step cost of the pair's joint states, ``joint_steps``. Both take
slot locations, so they serve the whole window's slots and a pair's narrowed ones.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.layers import Layers
from formulations.window.problem import WindowProblem


def slot_locations(problem: WindowProblem, grid: Layers) -> NDArray[np.float64]:
    """``(N, M + 2, K, D)`` location of every slot (0 where the slot is no node)."""
    location: NDArray[np.float64] = np.where(grid.valid[..., None], problem.node_location[grid.nodes(problem)], 0.0)
    return location


def chosen_locations(grid: Layers, location: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(N, M + 2, D)`` location of each object's chosen slot."""
    n, f = np.indices(grid.chosen.shape)
    chosen: NDArray[np.float64] = location[n, f, grid.chosen]
    return chosen


def partner_steps(
    moving: NDArray[np.float64], held: NDArray[np.float64], weight: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``(P, M + 1, K, K)`` layout steps of a moving object with slot locations ``moving``
    ``(P, M + 2, K, D)`` against a partner held at ``held`` ``(P, M + 2, D)``."""
    pairs, frames, width = moving.shape[0], moving.shape[1] - 2, moving.shape[2]
    steps = np.zeros((pairs, frames + 1, width, width))
    if frames < 2 or pairs == 0:
        return steps
    relative = moving[:, 1:-1] - held[:, 1:-1, None, :]  # (P, M, K, D)
    change = relative[:, 1:, None, :, :] - relative[:, :-1, :, None, :]  # (P, M-1, i, j, D)
    steps[:, 1:frames] = weight[:, None, None, None] * np.abs(change).sum(axis=-1)
    return steps


def joint_steps(
    first: NDArray[np.float64], second: NDArray[np.float64], weight: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``(P, M + 1, K, K, K, K)`` layout steps of pair p's joint states (i, j) -> (i', j'),
    from both objects' slot locations ``(P, M + 2, K, D)``."""
    pairs, frames, width = first.shape[0], first.shape[1] - 2, first.shape[2]
    steps = np.zeros((pairs, frames + 1, width, width, width, width))
    if frames < 2 or pairs == 0:
        return steps
    relative = first[:, 1:-1, :, None, :] - second[:, 1:-1, None, :, :]  # (P, M, i, j, D)
    change = relative[:, 1:, None, None] - relative[:, :-1, :, :, None, None]  # (P, M-1, i, j, i', j', D)
    steps[:, 1:frames] = weight[:, None, None, None, None, None] * np.abs(change).sum(axis=-1)
    return steps
