"""Recovery over a whole labeled take: three markers whose labels went round, given back on
the say of the labeled first frame.

A pair exchange (``take_exchange``) cannot undo a rotation: three near markers of one segment,
each on the next one's point. CMU 135_02 relabeled from frame 0: the file's own left foot is
corrupt from frame 4483 (a repeated frame, then LMT5 183 mm from LTOE instead of 94), and past
it the windows had the heel on the ankle's point, the ankle on the fifth metatarsal's and the
metatarsal on the heel's, for the remaining 700 frames: no pair of them exchanged gives any
marker its own point back, so no pair's gain clears.

A rotation is judged as an exchange is, with the costs of ``take_exchange``: for a triangle
(a, b, c) of markers rigid with each other and near in the first frame, each cyclic order
pi (a takes b's labels, b takes c's, c takes a's; or the other way round) gains in a frame
labeling all three

    g_t = sum_m c_m(x_m, t) - sum_m c_m(x_pi(m), t),

over the witnesses rigid with all three, sd_mj^2 = var_mj + var_pi(m)j. It may start and stop
where the rotated labels step nearer to where each marker was heading (its track continued
over gaps by the windows' fill) than the labels do, or after a frame labeling at most one of
the three (135_02's foot: two of them unlabeled for three frames, the fill heading where the
rotated labels went); it is made where the best run's sum reaches n / 2 times the exchange's
``EXCHANGE_NATS`` and ``MIN_RATE`` a frame for a permutation of n markers (the exchange's bars
are for two markers' costs, a rotation sums three: the wheelchair racing take with 10 ghosts a
frame, seed 1, rotated a wrist triangle on 86 nats over 362 frames at the exchange's bars,
77.56 -> 72.25 %), and where the rotated labels fit as right ones do in the run, and the labels
as they are outside it (mean capped cost per marker under ``FIT_COST``, as the exchange asks).
Pair exchanges go first; a rotation is looked for in what they leave. The search
(``permutations_given_back``) takes any permutation of a rigid set: ``take_flip`` gives a
plate of four read turned half round back with it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.heading import track_heading
from formulations.markers.pair_spread import PairSpreads
from formulations.markers.take_exchange import (
    EXCHANGE_NATS,
    FIT_COST,
    MIN_RATE,
    NEAREST,
    best_run,
    label_distance,
    near_pairs,
)
from formulations.markers.witness_costs import permutation_costs, rigid_witnesses

Array = NDArray[np.float64]


@dataclass(frozen=True)
class TakeRotation:
    """Over frames [start, stop) each of ``markers`` takes the labels of the next one (the
    last the first's)."""

    markers: tuple[int, int, int]
    start: int
    stop: int
    nats: float


def take_rotations(positions: Array, first: Array, neighbours: NDArray[np.int64], predicted: Array | None = None,
                   ) -> list[TakeRotation]:
    """The rotations that give a labeling back its first frame's shape (module doc), best
    first, each judged on the labels the ones before left; arguments as ``take_exchanges``."""
    known = np.asarray(np.isfinite(first).all(axis=1))
    near = near_pairs(neighbours, NEAREST) & known[:, None] & known[None, :]
    spreads = PairSpreads(positions)
    # each triangle turned either way: its markers in both orders, each taking the next one's labels
    sets = [[(o, o[1:] + o[:1]) for o in (t, (t[0], t[2], t[1]))] for t in _triangles(near) if _rigid_sides(spreads, t)]
    given = permutations_given_back(positions, first, neighbours, predicted, sets, spreads)
    return [TakeRotation((markers[0], markers[1], markers[2]), start, stop, nats) for (markers, _), start, stop, nats in given]


Permutation = tuple[tuple[int, ...], tuple[int, ...]]  # markers, and whose labels each takes


def permutations_given_back(
    positions: Array, first: Array, neighbours: NDArray[np.int64], predicted: Array | None,
    sets: Sequence[Sequence[Permutation]], spreads: PairSpreads,
) -> list[tuple[Permutation, int, int, float]]:
    """The permutations that give a labeling back its first frame's shape, with their frames
    [start, stop) and nats: of ``sets`` (each the permutations tried of one set of markers) the
    best that clears (``judged_permutation``) is made and the sets of its markers dropped, then
    the rest are judged again on the labels it left, until none clears. ``spreads``: of
    ``positions``."""
    d0 = np.linalg.norm(first[:, None] - first[None], axis=2)
    continued = positions if predicted is None else np.where(np.isfinite(positions), positions, predicted)
    working, done = np.stack([positions, continued]), []
    while sets:
        found = [((markers, taken), run) for tried in sets for markers, taken in tried
                 if (run := judged_permutation(working, list(markers), list(taken), neighbours, d0, spreads))]
        if not found:
            break
        (markers, taken), (start, stop, nats) = max(found, key=lambda f: f[1][2])
        working[:, start:stop, list(markers)] = working[:, start:stop, list(taken)]
        spreads = PairSpreads(working[0])  # the permuted labels' pairs spread otherwise
        done.append(((markers, taken), start, stop, nats))
        sets = [tried for tried in sets if {*tried[0][0]} != {*markers}]
    return done


def _triangles(linked: NDArray[np.bool_]) -> list[tuple[int, int, int]]:
    """Every (a, b, c), a < b < c, whose three pairs are ``linked``."""
    out = []
    for a in range(len(linked)):
        later = [int(b) for b in np.flatnonzero(linked[a]) if b > a]
        out += [(a, b, c) for b, c in combinations(later, 2) if linked[b, c]]
    return out


def _rigid_sides(spreads: PairSpreads, triangle: tuple[int, int, int]) -> bool:
    """The triangle's three sides keep their lengths as a rigid pair's do (``PairSpreads.rigid``)."""
    rigid = spreads.rigid(list(triangle), list(triangle))
    return bool(rigid[0, 1] and rigid[0, 2] and rigid[1, 2])


def judged_permutation(tracks: Array, markers: list[int], taken: list[int], neighbours: NDArray[np.int64], d0: Array,
                       spreads: PairSpreads) -> tuple[int, int, float] | None:
    """Frames [start, stop) and the nats of the best run where ``markers[k]`` takes the labels
    of ``taken[k]`` (a permutation of ``markers``), None when it does not clear (module doc).
    ``tracks``: the labeled positions and the same continued over gaps by the prediction;
    ``spreads``: of the labeled positions."""
    positions = tracks[0]
    judges = rigid_witnesses(markers, neighbours, spreads, markers) + markers  # the set's own distances judge too
    right, rotated = permutation_costs(positions, markers, taken, judges, d0, spreads)
    every = np.isfinite(right) & np.isfinite(rotated) & np.isfinite(positions[:, markers]).all(axis=(1, 2))
    gain = np.where(every, right - rotated, 0.0)
    if gain[1:][gain[1:] > 0].sum() < EXCHANGE_NATS:
        return None
    start, stop, nats = best_run(gain, _may_turn(tracks, markers, taken))
    inside = np.zeros(len(every), bool)
    inside[start:stop] = True
    if nats < len(markers) / 2 * max(EXCHANGE_NATS, MIN_RATE * every[inside].sum()) or not (every & inside).any():
        return None
    outside = every & ~inside
    outside[0] = False  # the first frame is d0 itself
    # the rotated labels fit as right ones do, and so do the labels outside the run (as the
    # exchange asks: a set whose right labels do not keep the first frame is no judge)
    if _fit(rotated[every & inside], len(markers)) > FIT_COST or _fit(right[outside], len(markers)) > FIT_COST:
        return None
    return start, stop, nats


def _fit(cost: Array, n: int) -> float:
    """Mean cost per marker over the frames given (the ``n`` markers' sum), 0 for none."""
    return float(np.mean(cost)) / n if len(cost) else 0.0


def _may_turn(tracks: Array, markers: list[int], taken: list[int]) -> NDArray[np.bool_]:
    """``(F + 1,)`` where the rotation may start or stop (module doc)."""
    labels, continued = tracks[0], tracks[1]
    heading = {m: track_heading(continued[:, m]) for m in markers}
    kept = sum(label_distance(labels[:, m], heading[m]) for m in markers)
    crossed = sum(label_distance(labels[:, t], heading[m]) for m, t in zip(markers, taken))
    # the pair's "neither labeled": with all but one unseen, nothing seen says which came back where
    lost = (~np.isfinite(labels[:, markers]).all(axis=2)).sum(axis=1) >= len(markers) - 1
    return np.append((crossed < kept) | np.append(False, lost[:-1]), True)
