"""Margins of the readings that move two objects together (``margins``, second kind).

A pair (a, b) is worth moving together when a slot of one is held by the other's chosen
path, or when they form a layout pair. Within the pair a slot is usable when no third,
held, object needs its resources; the pair's programme (``pairs``) runs over the usable
slots only, narrowed per pair (a marker re-acquiring through a wide gate has many
candidates, but few that one given partner holds), and pairs of similar width are
batched. A slot whose margin is proven above the horizon is dropped too: a reading of
the pair through slot u of a costs at least a's cheapest path through u plus b's
cheapest path, conflicts ignored (``single``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.held import FREE, exclusive_pairs
from formulations.confidence.layers import Layers
from formulations.confidence.layout_steps import chosen_locations, joint_steps, partner_steps
from formulations.confidence.pairs import pair_min_marginals
from formulations.window.problem import WindowProblem

PAIR_BUCKET = 4  # pairs up to this many usable slots per frame share a batch; wider ones get their own


def lower_pair_margins(
    problem: WindowProblem, grid: Layers, holder: NDArray[np.intp], relaxed: NDArray[np.float64],
    location: NDArray[np.float64], horizon: float, margin: NDArray[np.float64],
) -> None:
    """Lower ``margin`` ``(N, M, K)`` by every worthwhile pair's joint min-marginals (in place).

    Args:
        relaxed: ``(N, M, K)`` each object's own min-marginals minus its chosen path's
            cost, conflicts ignored: the bound used to drop slots beyond ``horizon``.
        location: ``(N, M + 2, K, D)`` slot locations (used only with layout pairs).
    """
    lay = problem.layout_pairs[problem.layout_weight > 0]
    first, second, weight = _worthwhile(problem.n_objects, holder, lay, problem.layout_weight[problem.layout_weight > 0])
    best = relaxed[:, 0].min(axis=1)  # each object's cheapest path minus its chosen one: <= 0
    usable_a = _usable(grid, holder, relaxed, first, second, horizon - best[second])
    usable_b = _usable(grid, holder, relaxed, second, first, horizon - best[first])
    width = np.maximum(usable_a.sum(axis=2).max(axis=1, initial=1), usable_b.sum(axis=2).max(axis=1, initial=1))
    bucket = np.where(weight > 0, -1, width > PAIR_BUCKET)  # wide pairs apart; layout pairs apart (K^4)
    nodes = exclusive_pairs(problem)
    for value in np.unique(bucket):
        batch = np.flatnonzero(bucket == value)
        pair = _Narrowed(grid, first[batch], second[batch], usable_a[batch], usable_b[batch])
        a, b, joint = pair.steps(grid, location, weight[batch])
        allowed = pair.valid_a[..., :, None] & pair.valid_b[..., None, :]
        pair.exclude_shared(problem, grid, nodes, allowed)
        marginal = pair_min_marginals(a, b, allowed, joint)
        base = _path_cost(pair.chosen_a, pair.chosen_b, a, b, joint)
        _lower(margin, first[batch], pair.order_a[:, 1:-1],
               np.where(pair.valid_a[:, 1:-1], marginal.min(axis=3) - base[:, None, None], np.inf))
        _lower(margin, second[batch], pair.order_b[:, 1:-1],
               np.where(pair.valid_b[:, 1:-1], marginal.min(axis=2) - base[:, None, None], np.inf))


def _lower(margin: NDArray[np.float64], objects: NDArray[np.intp], slots: NDArray[np.intp],
           value: NDArray[np.float64]) -> None:
    """``margin[objects[p], t, slots[p, t, k]]`` lowered to ``value[p, t, k]`` where that is less (in place).

    By flat index: ``np.minimum.at`` takes a tuple of index arrays 4-5x slower.
    """
    flat = np.reshape(margin, -1, copy=False)
    frames, width = margin.shape[1:]
    index = (objects[:, None, None] * frames + np.arange(frames)[None, :, None]) * width + slots
    np.minimum.at(flat, index.ravel(), value.ravel())


def _worthwhile(
    n: int, holder: NDArray[np.intp], lay: NDArray[np.intp], mu: NDArray[np.float64],
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """Pairs (first < second): a slot of one held by the other, or a layout pair; and the
    total mu of the layout pairs joining them (0 for none)."""
    contest = holder >= 0
    owner, other = np.nonzero(contest)[0], holder[contest]
    laid = lay.min(axis=1) * n + lay.max(axis=1)
    key = np.unique(np.concatenate([np.minimum(owner, other) * n + np.maximum(owner, other), laid]))  # sorted (first, second)
    weight = np.zeros(len(key))
    np.add.at(weight, np.searchsorted(key, laid), mu)
    first, second = np.divmod(key, n)
    return first, second, weight


def _usable(
    grid: Layers, holder: NDArray[np.intp], relaxed: NDArray[np.float64], moving: NDArray[np.intp],
    partner: NDArray[np.intp], reach: NDArray[np.float64],
) -> NDArray[np.bool_]:
    """``(P, M + 2, K)`` slots of ``moving`` free of third parties and within ``reach``, chosen ones always."""
    own = holder[moving]
    usable: NDArray[np.bool_] = grid.valid[moving] & ((own == FREE) | (own == partner[:, None, None]))
    usable[:, 1:-1] &= relaxed[moving] <= reach[:, None, None]
    p, f = np.indices(grid.chosen[moving].shape)
    usable[p, f, grid.chosen[moving]] = True
    return usable


class _Narrowed:
    """A batch of pairs, each object's usable slots first (``order``), cut to one width."""

    def __init__(self, grid: Layers, first: NDArray[np.intp], second: NDArray[np.intp],
                 usable_a: NDArray[np.bool_], usable_b: NDArray[np.bool_]) -> None:
        width = max(int(usable_a.sum(axis=2).max()), int(usable_b.sum(axis=2).max()), 1)
        self.first, self.second = first, second
        self.order_a = np.argsort(~usable_a, axis=2, kind="stable")[..., :width]
        self.order_b = np.argsort(~usable_b, axis=2, kind="stable")[..., :width]
        self.valid_a = np.take_along_axis(usable_a, self.order_a, axis=2)
        self.valid_b = np.take_along_axis(usable_b, self.order_b, axis=2)
        self.chosen_a = np.argmax(self.order_a == grid.chosen[first][..., None], axis=2)
        self.chosen_b = np.argmax(self.order_b == grid.chosen[second][..., None], axis=2)

    def steps(self, grid: Layers, location: NDArray[np.float64], weight: NDArray[np.float64]) -> tuple[
            NDArray[np.float64], NDArray[np.float64], NDArray[np.float64] | None]:
        """Both objects' narrowed steps; with a layout pair, its term moved from the held
        partner's steps into the joint ones."""
        a, b = _narrow(grid, self.first, self.order_a), _narrow(grid, self.second, self.order_b)
        if not (weight > 0).any():
            return a, b, None
        at_a, at_b = _slots(location[self.first], self.order_a), _slots(location[self.second], self.order_b)
        held = chosen_locations(grid, location)
        a = a - partner_steps(at_a, held[self.second], weight)
        b = b - partner_steps(at_b, held[self.first], weight)
        return a, b, joint_steps(at_a, at_b, weight)

    def exclude_shared(self, problem: WindowProblem, grid: Layers, nodes: NDArray[np.intp],
                       allowed: NDArray[np.bool_]) -> None:
        """Forbid joint states whose two nodes hold one resource (in place)."""
        u, w = nodes[:, 0], nodes[:, 1]
        swap = problem.node_object[u] > problem.node_object[w]
        u, w = np.where(swap, w, u), np.where(swap, u, w)
        n = problem.n_objects
        key = self.first * n + self.second  # sorted: pairs come from np.unique
        wanted = problem.node_object[u] * n + problem.node_object[w]
        pair = np.minimum(np.searchsorted(key, wanted), max(len(key) - 1, 0))
        found = np.flatnonzero(key[pair] == wanted) if len(key) else np.zeros(0, dtype=np.intp)
        pair, u, w = pair[found], u[found], w[found]
        frame = problem.node_frame[u]
        slot_u = _position(self.order_a[pair, frame], grid.slot(problem, u))
        slot_w = _position(self.order_b[pair, frame], grid.slot(problem, w))
        kept = (slot_u >= 0) & (slot_w >= 0)
        allowed[pair[kept], frame[kept], slot_u[kept], slot_w[kept]] = False


def _position(order: NDArray[np.intp], slot: NDArray[np.intp]) -> NDArray[np.intp]:
    """Where each ``slot`` sits in its row of ``order`` (``(E, W)``), -1 if cut."""
    hit = order == slot[:, None]
    position: NDArray[np.intp] = np.where(hit.any(axis=1), hit.argmax(axis=1), -1)
    return position


def _narrow(grid: Layers, objects: NDArray[np.intp], order: NDArray[np.intp]) -> NDArray[np.float64]:
    """``(P, M + 1, W, W)`` steps of ``objects[p]`` between the ordered slots of consecutive frames."""
    p = objects[:, None, None, None]
    f = np.arange(order.shape[1] - 1)[None, :, None, None]
    narrowed: NDArray[np.float64] = grid.step[grid.at(p, f, order[:, :-1, :, None], order[:, 1:, None, :])]
    return narrowed


def _slots(values: NDArray[np.float64], order: NDArray[np.intp]) -> NDArray[np.float64]:
    """``(P, M + 2, W, ...)`` per-slot values in ``order``."""
    gathered: NDArray[np.float64] = np.take_along_axis(values, order.reshape(order.shape + (1,) * (values.ndim - 3)), axis=2)
    return gathered


def _path_cost(
    chosen_a: NDArray[np.intp], chosen_b: NDArray[np.intp], a: NDArray[np.float64], b: NDArray[np.float64],
    joint: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """``(P,)`` each pair's chosen paths priced by its joint steps."""
    p, f = np.indices(chosen_a[:, :-1].shape)
    cost = a[p, f, chosen_a[:, :-1], chosen_a[:, 1:]] + b[p, f, chosen_b[:, :-1], chosen_b[:, 1:]]
    if joint is not None:
        cost = cost + joint[p, f, chosen_a[:, :-1], chosen_b[:, :-1], chosen_a[:, 1:], chosen_b[:, 1:]]
    total: NDArray[np.float64] = cost.sum(axis=1)
    return total
