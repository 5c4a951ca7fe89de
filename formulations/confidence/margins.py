"""How much more the best reading that changes a label costs than the chosen reading.

A *reading* of a window is one path per object (``WindowSolution.path``); its cost is the
window objective E (``window.objective``). For object n, frame t and a slot u of that
frame other than the chosen one, the margin is

    Delta(n, t, u) = min { E(Q) : Q feasible, Q_n(t) = u } - E(P),

P the chosen reading. The minimum runs here over the readings that move at most two
objects, the others held on P (``held``):

  * one object alone: its min-marginals (``single``) over the nodes no held object
    needs, with the layout terms to its held partners as step costs;
  * two objects together, for every pair where one needs a resource the other's path
    holds, or that is a layout pair: the joint min-marginals (``pair_moves``), which
    also see a swap, the usual way two markers trade names.

An object that shares no candidate and no layout pair with another (most of them) has
the exact margin: nobody else can be affected. Otherwise Delta is exact when the best
alternative moves at most two objects and is an upper bound when it needs three or more
(a chain of displaced markers). Delta < 0 means P is not even the cheapest reading
through its own label, as a heuristic's or a rounding's answer may be.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.held import FREE, foreign_holder
from formulations.confidence.layers import Layers, layers
from formulations.confidence.layout_steps import chosen_locations, partner_steps, slot_locations
from formulations.confidence.pair_moves import lower_pair_margins
from formulations.confidence.single import min_marginals
from formulations.window.problem import WindowProblem


def reading_margins(
    problem: WindowProblem, path: NDArray[np.intp], horizon: float = np.inf,
) -> tuple[NDArray[np.float64], Layers]:
    """``(N, M, K)`` Delta(n, t, u) over each block's slots, and the layered view.

    Delta is 0 or below at the chosen slot and inf at slots that are no node or that no
    move of one or two objects reaches. ``horizon`` only saves time: two-object moves
    whose margin is proven above it are not searched, so a margin above ``horizon`` may
    come out larger than it is (or inf); every margin up to it is as without it.
    """
    grid = layers(problem, path)
    lay = problem.layout_pairs[problem.layout_weight > 0]
    location = slot_locations(problem, grid) if len(lay) else np.zeros(grid.valid.shape + (0,))
    if len(lay):  # each object's layout terms to its partners held on their paths
        mu = problem.layout_weight[problem.layout_weight > 0]
        held = chosen_locations(grid, location)
        own = grid.step.copy()  # a slot past an object's steps adds to the inf after them all
        np.add.at(own, _steps_of(grid, lay[:, 0]), partner_steps(location[lay[:, 0]], held[lay[:, 1]], mu))
        np.add.at(own, _steps_of(grid, lay[:, 1]), partner_steps(location[lay[:, 1]], held[lay[:, 0]], mu))
        grid = replace(grid, step=own)
    holder: NDArray[np.intp] = np.where(grid.valid, foreign_holder(problem, path)[grid.nodes(problem)], FREE)
    cost = grid.path_cost(grid.step)[:, None, None]
    # each object alone: conflicts ignored, and kept off the held paths' resources
    relaxed, margin = min_marginals(grid, grid.step, np.stack([grid.valid, grid.valid & (holder == FREE)])) - cost
    lower_pair_margins(problem, grid, holder, relaxed, location, horizon, margin)
    return margin, grid


def _steps_of(grid: Layers, objects: NDArray[np.intp]) -> NDArray[np.intp]:
    """``(P, M + 1, K, K)`` index in ``grid.step`` of every step of each of ``objects``."""
    frame, tail, head = np.indices((grid.chosen.shape[1] - 1, grid.width, grid.width))
    return grid.at(objects[:, None, None, None], frame, tail, head)
