"""Alternatives that leave a label where it is: another point at exactly the chosen point's place.

A label says where a marker (or object) is. Some files carry a column twice (HDM05's ``*0``,
``*1`` and ``*2`` repeat LFHD, CLAV and LFWT to the micrometre), so a frame holds two points
at one position, and the reading through the copy costs exactly what the chosen one does.
Counted as an alternative, that tie held each such label at p = 1/2 for the whole take
(on HDM05 relabeled from its file, 11,967 right labels, 7.3 % of the take, all doubtful).
But both readings put the marker at the same place: the label is the same either way.

So the probability of a label is that of the readings that put it there. With S the other
slots at the chosen slot's location and O the rest,

    p(n, t) = (1 + sum_{u in S} exp(-Delta(n, t, u))) / (1 + sum_{u in S u O} exp(-Delta(n, t, u))),

and the label's margin is the least Delta over O. Only observation nodes with equal
coordinates count: two measured points are never equal to the last bit unless one is a copy
of the other, and an occlusion node's location is a prediction, not a place the marker was seen.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.layers import Layers
from formulations.window.problem import OBSERVATION, WindowProblem


def same_place(problem: WindowProblem, grid: Layers) -> NDArray[np.bool_]:
    """``(N, M, K)`` slots of frames 1..M, other than the chosen one, that are observations at
    exactly the chosen observation's location (none where the chosen slot is an occlusion)."""
    nodes = grid.nodes(problem)[:, 1:-1]
    observed = grid.valid[:, 1:-1] & (problem.node_kind[nodes] == OBSERVATION)
    chosen = grid.chosen[:, 1:-1, None]
    at_chosen = np.take_along_axis(observed, chosen, axis=2)
    location = problem.node_location[nodes]
    chosen_location = np.take_along_axis(location, chosen[..., None], axis=2)
    same: NDArray[np.bool_] = observed & at_chosen & (location == chosen_location).all(axis=-1)
    np.put_along_axis(same, chosen, False, axis=2)
    return same
