"""Recovery over a whole labeled take: two markers the windows exchanged, given back on the
say of the labeled first frame.

The window repairs (``exchange``, ``pair_evidence``) judge an exchange by the distances the
marker state has learned, and those follow the labels: a pair exchanged before its
distances were learned, or kept exchanged for longer than the ~33 frames the statistics
take to adapt, fits its learned shape either way. Hamner's running take at 2 mm noise: the
right wrist's radial and ulnar markers, 63 mm apart, 271 +- 4 and 259 +- 3 mm from the
elbow (their one rigid neighbour), exchanged at frame 83 and kept so for 500 frames.

The first frame, which the user labeled, does not adapt. A pair (a, b) rigid with each other
over the take (distance sd under ``RIGID_SD_MM``, ``take_spread``: robust to a tenth of wrong
labels) and near (one among the other's ``NEAREST`` nearest in the first frame: a returning
marker takes a point for its own where the two are close; the back and a shoulder, 200 mm
apart, were exchanged on the say of a sternum a stooping trunk moved) is judged by its
witnesses: the markers rigid with both. With d0_mj the first frame's distance of marker m
to witness j and var_mj the take's spread, the cost of m at x in frame t is

    c_m(x, t) = mean_j min(z_mj^2, CAP^2) / 2,   z_mj = (||x - r_j(t)|| - d0_mj) / sd_j,
    sd_j^2 = var_aj + var_bj,

over the witnesses seen at t. In a frame where both are labeled the exchange gains

    g_t = c_a(x_a) + c_b(x_b) - c_a(x_b) - c_b(x_a),

which (uncapped) is -(d_a - d_b)(d0_a - d0_b) / sd^2 per witness: whether the two sit as
they sat in the first frame, blind to an offset both distances share (a pose the first frame
did not have moves both). One marker's distance alone is not: a running wrist's pose moves
the radial marker's distance to the elbow by as much as the 12 mm that tells it from the
ulnar one, so a frame that labels one of them only gives no evidence.

The pair is exchanged over the frames [s, e) that maximise sum g_t (frame 0 is the user's
and never changes) among those an exchange can start and stop at: where the labels step
farther from where each marker was heading (its track continued over gaps by the windows'
prediction) than the exchanged labels would, or after a frame that labels neither (then
nothing seen says which came back on whose point). Elsewhere the exchange would put jumps
into two smooth tracks, or give a marker a point too far off for it to have been taken. It
is made where

- the sum reaches ``EXCHANGE_NATS`` and ``MIN_RATE`` per frame labeling both: a pose the
  first frame did not have biases a pair's distances slowly, and over hundreds of frames
  sums to as much as a true exchange gives in tens (CMU HDM05 at 4 mm: the sternum and a
  shoulder marker, 1.8 mm apart in their distance to T10, 67 nats over 268 frames);
- the exchanged labels fit as right labels do, and so do the labels outside the run: the
  pair's difference of distances to each witness keeps the first frame's, mean capped
  e^2 / 2 at most ``FIT_COST`` with e_j = ((d_a - d_b) - (d0_a - d0_b)) / sd_j, offset-blind
  as the gain is. A pair whose witnesses do not keep the first frame where it is labeled
  right is no judge of where it is not. (Each distance against its own d0 is no such test:
  OpenSim's walking knee pair, LMFC and LKJC, exchanged for 174 frames, fits at 1.3-1.6
  that way, right or exchanged, as the knee flexes from the first frame's stance, and at
  0.12-0.14 by the difference.) A witness term beyond ``CAP`` both ways, as labeled and as
  exchanged, fits neither reading (the witness or the pair on foreign points) and is left
  out of both fits (``_judging``); a run whose terms are mostly such has no judge and is not
  made.

A pair that no marker is rigid with (a head left with two markers) is judged the same way by
its witnesses by difference (``difference_witnesses``): markers whose difference of distances
to the two keeps its sign and size over the take, one cost per witness on that difference.
Those pin no absolute distance, so the run must also keep the pair's own distance, which an
exchange of the two leaves as it was (``pair_offset``).

Best exchanges first, every pair judged again after each, until none clears. Distances
cannot see a reflection (``mirror``) nor a plate's symmetry (``turns``): those gain nothing
here and are left alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.difference_witnesses import difference_witnesses, fit_spread, pair_offset
from formulations.markers.heading import track_heading
from formulations.markers.state import RIGID_SD_MM
from formulations.markers.take_spread import take_spread

Array = NDArray[np.float64]

CAP = 3.0  # z beyond 3 sd counts as 3: a slipped neighbour or a foreign point, not more evidence
EXCHANGE_NATS = 20.0  # as the window's pair evidence: frames are not independent (skin motion is slow)
NEAREST = 3  # a pair is among either's three nearest in the first frame: a plate, a wrist, a forefoot
MIN_RATE = 0.5  # nats a frame labeling both must give on average: a pose's slow bias gives less
JUDGED_SHARE = 0.5  # of the run's witness terms within CAP either way (``_judging``): else no judge
FIT_COST = 1.0  # mean capped e^2 / 2 of a right pair: about 0.1-0.4 (sd_j^2 is two spreads)


@dataclass(frozen=True)
class TakeExchange:
    """Markers ``a`` and ``b`` exchange their labels over frames [start, stop)."""

    a: int
    b: int
    start: int
    stop: int
    nats: float

    @property
    def markers(self) -> tuple[int, int]:
        """The two markers, each taking the other's labels (as ``TakeRotation.markers``)."""
        return self.a, self.b


def take_exchanges(
    positions: Array, first: Array, neighbours: NDArray[np.int64], predicted: Array | None = None,
) -> list[TakeExchange]:
    """The exchanges that give a labeling back its first frame's shape (module doc), in the
    order they apply.

    Args:
        positions: ``(F, N, 3)`` labeled positions, NaN where a marker has no label.
        first: ``(N, 3)`` the labeled first frame (NaN for a marker it lacks).
        neighbours: ``(N, K)`` each marker's neighbours (``MarkerState.neighbours``).
        predicted: ``(F, N, 3)`` where each unlabeled marker was predicted to be (the windows'
            fill), NaN elsewhere; without it an unlabeled marker is where it was last labeled.
    """
    spread, rigid = rigid_pairs(positions, first, neighbours)
    d0 = np.linalg.norm(first[:, None] - first[None], axis=2)
    n = len(first)
    pairs = [(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(rigid & near_pairs(neighbours, NEAREST), 1)))]
    continued = positions if predicted is None else np.where(np.isfinite(positions), positions, predicted)
    working, done = np.stack([positions, continued]), []
    nearby = {(a, b): np.union1d(neighbours[a], neighbours[b]) for a, b in pairs}
    judged = {pair: _judged(working, *pair, rigid, d0, spread, nearby[pair]) for pair in pairs}
    for _ in range(n):
        found = [e for e in judged.values() if e is not None]
        if not found:
            break
        best = max(found, key=lambda e: e.nats)
        moved = [best.a, best.b]
        working[:, best.start : best.stop, moved] = working[:, best.start : best.stop, moved[::-1]]
        done.append(best)
        for a, b in pairs:  # judged again: the pairs the exchange moved, or moved a witness of
            if a in moved or b in moved or (rigid[a, moved] & rigid[b, moved]).any() or np.isin(moved, nearby[a, b]).any():
                judged[a, b] = _judged(working, a, b, rigid, d0, spread, nearby[a, b])
    return done


def near_pairs(neighbours: NDArray[np.int64], k: int) -> NDArray[np.bool_]:
    """``(N, N)`` pairs where one marker is among the other's ``k`` nearest (``neighbours``
    nearest first)."""
    n = len(neighbours)
    near = np.zeros((n, n), bool)
    near[np.repeat(np.arange(n), min(k, neighbours.shape[1])), neighbours[:, :k].ravel()] = True
    near |= near.T
    return near


def rigid_pairs(positions: Array, first: Array, neighbours: NDArray[np.int64]) -> tuple[Array, NDArray[np.bool_]]:
    """``(N, N)`` the take's spread of each neighbour pair's distance (``take_spread``; inf for
    a pair that is not neighbours), and which pairs are rigid and both in the first frame."""
    n = len(first)
    spread = np.full((n, n), np.inf)
    spread[np.repeat(np.arange(n), neighbours.shape[1]), neighbours.ravel()] = take_spread(positions, neighbours).ravel()
    spread = np.fmin(spread, spread.T)  # NaN (too few frames together) and inf both compare False below
    known = np.asarray(np.isfinite(first).all(axis=1))
    rigid: NDArray[np.bool_] = (spread <= RIGID_SD_MM**2) & known[:, None] & known[None, :]
    return spread, rigid


def _judged(tracks: Array, a: int, b: int, rigid: NDArray[np.bool_], d0: Array, spread: Array,
            nearby: NDArray[np.int64]) -> TakeExchange | None:
    """The pair's exchange over its best frames, None when it does not clear (module doc).
    ``tracks``: the labeled positions and the same continued over gaps by the prediction;
    ``nearby``: the pair's neighbours, its witnesses by difference (``difference_witnesses``)
    where no marker is rigid with both."""
    positions = tracks[0]
    witness = rigid[a] & rigid[b]
    witness[[a, b]] = False
    j = np.flatnonzero(witness)
    own, other = positions[:, a], positions[:, b]
    judged = _rigid_costs(positions, a, b, j, d0, spread) if j.size else _difference_costs(positions, a, b, nearby, d0)
    if judged is None:
        return None
    right, swapped, apart, apart0, sd = judged
    both = np.isfinite(right) & np.isfinite(swapped)
    gain = np.where(both, right - swapped, 0.0)
    if gain[1:][gain[1:] > 0].sum() < EXCHANGE_NATS:  # no run can reach it: spare the turns
        return None
    start, stop, nats = best_run(gain, may_exchange(own, other, tracks[1][:, a], tracks[1][:, b]))
    inside = np.zeros(len(both), bool)
    inside[start:stop] = True
    outside = both & ~inside
    outside[0] = False  # the first frame is d0 itself
    if nats < max(EXCHANGE_NATS, MIN_RATE * both[inside].sum()) or not (both & inside).any():
        return None
    judging = _judging(apart, apart0, sd)
    if judging[both & inside].sum() < JUDGED_SHARE * np.isfinite(apart[both & inside]).sum():
        return None  # the run's witnesses mostly sit on foreign points: nothing judges its fit
    apart = np.where(judging, apart, np.nan)
    if _fit((-apart[both & inside] - apart0) / sd) > FIT_COST or _fit((apart[outside] - apart0) / sd) > FIT_COST:
        return None
    if not j.size and _fit(pair_offset(own[both & inside], other[both & inside], d0[a, b], spread[a, b])) > FIT_COST:
        return None
    return TakeExchange(a, b, start, stop, nats)


def _rigid_costs(positions: Array, a: int, b: int, j: NDArray[np.int64], d0: Array, spread: Array,
                 ) -> tuple[Array, Array, Array, Array, Array]:
    """``(F,)`` the labels' and the exchanged labels' costs against the rigid witnesses ``j``
    (module doc), the pair's ``(F, W)`` differences of distances to them, the first frame's
    ``(W,)`` and their ``(W,)`` sds."""
    sd = np.sqrt(spread[a, j] + spread[b, j])
    to_own, to_other = (np.linalg.norm(positions[:, [m]] - positions[:, j], axis=2) for m in (a, b))  # (F, W)
    right = capped_cost((to_own - d0[a, j]) / sd) + capped_cost((to_other - d0[b, j]) / sd)
    swapped = capped_cost((to_other - d0[a, j]) / sd) + capped_cost((to_own - d0[b, j]) / sd)
    return right, swapped, to_own - to_other, d0[a, j] - d0[b, j], sd


def _difference_costs(positions: Array, a: int, b: int, nearby: NDArray[np.int64], d0: Array,
                      ) -> tuple[Array, Array, Array, Array, Array] | None:
    """As ``_rigid_costs``, by the witnesses by difference among ``nearby``; the costs (the
    gain) at s_j, the sds returned widened by the pose (``fit_spread``: the fit and which of its
    terms judge, ``_judging``); None when there are none."""
    by_difference = difference_witnesses(positions, a, b, nearby, d0)
    if by_difference is None:
        return None
    apart, apart0, sd = by_difference
    right, swapped = capped_cost((apart - apart0) / sd), capped_cost((-apart - apart0) / sd)
    return right, swapped, apart, apart0, fit_spread(apart, apart0, sd)


def best_run(gain: Array, may_turn: NDArray[np.bool_]) -> tuple[int, int, float]:
    """The frames [start, stop) with the largest sum of ``gain`` that start and stop where
    ``may_turn`` (``(F + 1,)``; frame F, the take's end, always may), frame 0 (the user's) left
    out; and that sum (a maximum subarray, by prefix sums). (0, 0, -inf) when no run may."""
    total = np.concatenate([[0.0], np.cumsum(gain)])  # total[t]: sum of gain[:t]
    starts = np.where(may_turn, total, np.inf)
    starts[[0, -1]] = np.inf
    low = np.minimum.accumulate(starts)[:-1]  # least allowed prefix before each stop
    may_stop = np.append(may_turn[1:-1], True)
    ends = np.where(may_stop & np.isfinite(low), total[1:] - low, -np.inf)
    stop = int(np.argmax(ends)) + 1
    if not np.isfinite(ends[stop - 1]):
        return 0, 0, -np.inf
    start = int(np.flatnonzero(starts[:stop] == low[stop - 1])[-1])
    return start, stop, float(total[stop] - total[start])


def may_exchange(own: Array, other: Array, own_continued: Array, other_continued: Array) -> NDArray[np.bool_]:
    """``(F + 1,)`` frames where an exchange of the pair may start or stop: where the labels
    step farther from where each marker was heading (``heading.track_heading`` of its track continued over
    gaps) than the exchanged labels would, or after a frame that labels neither (both were
    predicted there: which returned on whose point, nothing seen says). Elsewhere an exchange
    would put a jump into two tracks, or exchange markers too far apart for one to have taken
    the other's point."""
    heading = [track_heading(own_continued), track_heading(other_continued)]
    kept = label_distance(own, heading[0]) + label_distance(other, heading[1])
    crossed = label_distance(other, heading[0]) + label_distance(own, heading[1])
    neither = np.asarray(~np.isfinite(own).all(axis=1) & ~np.isfinite(other).all(axis=1))
    return np.append((crossed < kept) | np.append(False, neither[:-1]), True)


def label_distance(x: Array, y: Array) -> Array:
    """``(F,)`` distance, 0 where either is NaN (a marker without a label steps nowhere)."""
    distance: Array = np.nan_to_num(np.linalg.norm(x - y, axis=1), nan=0.0)
    return distance


def _judging(apart: Array, apart0: Array, sd: Array) -> NDArray[np.bool_]:
    """``(F, W)`` where a witness judges the pair's fit: within ``CAP`` sds of the first frame's
    difference as labeled or as exchanged. Beyond it both ways the witness sits on a foreign
    point or the pair on two others' points: it fits neither reading, so it says nothing of
    whether the exchanged labels fit as right ones do, and the fit must not count it against
    either (a witness by difference adds nothing to the gain there either, its one term capped
    both ways; a rigid witness's two distances may still). CMU 135_02's left heel and fifth
    metatarsal, exchanged for 360 frames, were refused on a toe marker the file itself holds
    100 mm off the foot."""
    return (np.abs(apart - apart0) < CAP * sd) | (np.abs(apart + apart0) < CAP * sd)


def _fit(e: Array) -> float:
    """Mean over frames of ``capped_cost(e)``, e_j = ((d_a - d_b) - (d0_a - d0_b)) / sd_j: how the
    pair's difference of distances to each witness keeps the first frame's (0 for no frame
    with a witness judging: ``_judging``)."""
    cost = capped_cost(e)
    return float(np.nanmean(cost)) if np.isfinite(cost).any() else 0.0


def capped_cost(z: Array) -> Array:
    """``(F,)`` mean over the witnesses seen in each frame of min(z^2, CAP^2) / 2 (``z``:
    ``(F, W)``, NaN where x or the witness is unlabeled); NaN where none is seen."""
    terms = np.minimum(z**2, CAP**2) / 2.0
    seen = np.isfinite(terms).sum(axis=1)
    with np.errstate(invalid="ignore"):
        return np.where(seen > 0, np.nansum(terms, axis=1) / np.maximum(seen, 1), np.nan)
