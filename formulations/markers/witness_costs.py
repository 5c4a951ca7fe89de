"""How markers rigid with a set of markers judge a permutation of the set's labels, frame by
frame, against the labeled first frame.

For markers m of the set, each taking the labels of pi(m) under the permutation, and judges j
(witnesses rigid with every marker of the set, and the set's own markers where they judge too),

    right_t   = sum_m c((|x_m,t - x_j,t| - d0_mj) / sd_mj),
    permuted_t = sum_m c((|x_pi(m),t - x'_j,t| - d0_mj) / sd_mj),

with c the capped cost of ``take_exchange.capped_cost`` (mean over the judges seen, each z
capped at ``CAP``), x'_j where judge j sits under the permutation, and sd_mj^2 = var_mj +
var_pi(m)j the two pairs' take spreads (``PairSpreads``). ``take_rotation`` makes a
permutation where the permuted costs are lower by its bars; ``plate_turns`` lets the same
witnesses deny a turn of a plate read from the plate's own corners alone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.pair_spread import PairSpreads
from formulations.markers.take_exchange import EXCHANGE_NATS, MIN_RATE, capped_cost

Array = NDArray[np.float64]


def rigid_witnesses(markers: list[int], neighbours: NDArray[np.int64], spreads: PairSpreads,
                    outside: list[int]) -> list[int]:
    """The first frame's neighbours of ``markers``, not in ``outside``, rigid with every one of them."""
    near = [int(j) for j in np.unique(neighbours[markers]) if j not in outside]
    return [j for j, ok in zip(near, np.asarray(spreads.rigid(markers, near).all(axis=0)), strict=True) if ok]


def permutation_costs(positions: Array, markers: list[int], taken: list[int], judges: list[int], d0: Array,
                      spreads: PairSpreads) -> tuple[Array, Array]:
    """``(F,)`` each: the labels' costs and the permuted labels' (module doc), NaN where no
    judge is seen. ``d0``: the first frame's distances; ``spreads``: of ``positions``."""
    var = spreads.var(markers, judges)
    right, permuted = np.zeros(len(positions)), np.zeros(len(positions))
    for k, (m, t) in enumerate(zip(markers, taken, strict=True)):
        others = [i for i, j in enumerate(judges) if j != m]
        sd = np.sqrt(var[k, others] + var[markers.index(t), others])
        jud = [judges[i] for i in others]
        # the set's other markers, in the permuted labeling, sit on the points they take
        where = np.stack([positions[:, taken[markers.index(j)]] if j in markers else positions[:, j] for j in jud], axis=1)
        right = right + capped_cost((np.linalg.norm(positions[:, m][:, None] - positions[:, jud], axis=2) - d0[m, jud]) / sd)
        permuted = permuted + capped_cost((np.linalg.norm(positions[:, t][:, None] - where, axis=2) - d0[m, jud]) / sd)
    return right, permuted


def witnesses_deny(positions: Array, first: Array, neighbours: NDArray[np.int64], spreads: PairSpreads,
                   markers: list[int], taken: list[int], outside: list[int], run: slice) -> bool:
    """Whether the witnesses of ``markers`` (``rigid_witnesses``, none of ``outside``) favour the
    labels over the permutation over frames ``run`` by the bar a take-wide permutation must
    clear to be made (``take_rotation``: n / 2 times max(``EXCHANGE_NATS``, ``MIN_RATE`` a
    judged frame)); False without witnesses. ``spreads``: of ``positions``."""
    witnesses = rigid_witnesses(markers, neighbours, spreads, outside)
    if not witnesses:
        return False
    d0 = np.linalg.norm(first[:, None] - first[None], axis=2)
    right, permuted = permutation_costs(positions[run], markers, taken, witnesses, d0, spreads)
    judged = np.isfinite(right) & np.isfinite(permuted)
    nats = float(np.sum(permuted[judged] - right[judged]))
    return nats >= len(markers) / 2 * max(EXCHANGE_NATS, MIN_RATE * float(judged.sum()))
