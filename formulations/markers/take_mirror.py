"""Recovery over a whole labeled take: two markers exchanged with each other's mirror image,
given back by handedness.

The take-wide exchange (``take_exchange``) judges a pair by its distances to witnesses rigid
with both. A toe and a fifth-metatarsal marker have one such witness at most (the heel: the
ankle crosses a joint), nearly as far from either, so their exchange keeps every distance
(HDM05 whole take, seed 0: RTOE and RMT5 exchanged over frames 1383-1965, in every reading of
the windows; the heel's costs 62.7 for the labels against 61.0 exchanged). Handedness is not
blind (``first_frame_handedness``): each of the 490 judged wrong labels of either flips its
quadruple with its three rigid mates (the other of the pair, heel, ankle) off the labeled
first frame, and none of their 1,547 judged right ones.

For two markers a, b each among the other's rigid mates (``first_frame_shape.rigid_mates``),
exchanging their labels in frame t gains

    g_t = sum over m in {a, b} of  flip_m,t(labels) - flip_m,t(exchanged),

flip 1 where m's quadruple is flipped off the first frame and 0 where kept; g_t = 0 where
either labeling leaves either quadruple unjudged. An exchange turns both quadruples over; a
pose that turns one marker's loose mate across the others' plane turns one (03_rolling, the
hard preset, seed 1: LLFHD's quadruple with the right elbow's LR_HLE flipped over 197-224
while LLBHD's was judged once; the exchange made on it, and the next on what it left, cost
100 labels). Only a quadruple that keeps clear of flat (``mirror.MIN_SINE``) in all but
``FLAT_SHARE`` of the frames labeling it judges: one that is often flat turns through flat
with the pose (HDM05's wrist, LWRA with LWRB, LFRM and LFIN: flat in 54 % of its labeled
frames, its sign turned over 16 % of its right labels; the foot's never flat).

The exchange is made over the run of largest gain (``take_exchange.best_run``, starting and
stopping where an exchange may: ``take_exchange.may_exchange``) where the labels are the
mirrored side against the exchanged ones (``first_frame_handedness.mirrored_side``: most of
their judged labels there flipped, almost none of the exchanged) and the exchange unflips at
least ``MIN_UNFLIPPED`` labels. The pair of largest gain goes first; the rest are judged again
on the labels it leaves, as the take-wide exchanges are.

Measured (2026-12-06, after the plate turns' witnesses; ``docs/measured.md``): HDM05 whole,
default and 2 mm, seeds 0-1, 99.28 / 99.27 -> 99.99 / 99.99 % (``nn-hungarian`` 99.27 / 99.25);
seed-0 accuracy matrix 2 rows up, none down; seeds 1-2 (with the witnesses) 8 up and 2 down of
170 against neither.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.first_frame_handedness import handedness_flips, mirrored_side
from formulations.markers.first_frame_shape import PARTNERS, rigid_mates
from formulations.markers.take_exchange import best_run, may_exchange

Array = NDArray[np.float64]

MIN_UNFLIPPED = 10  # labels a take-wide exchange must unflip: a few may be a flat moment's noise
FLAT_SHARE = 0.1  # of the frames labeling a quadruple: one flat more often turns through flat with the pose


@dataclass(frozen=True)
class TakeMirror:
    """Markers ``a`` and ``b`` exchange their labels over frames [start, stop), which unflips
    ``unflipped`` labels' handedness."""

    a: int
    b: int
    start: int
    stop: int
    unflipped: float

    @property
    def markers(self) -> tuple[int, int]:
        """The two markers, each taking the other's labels (as ``TakeExchange.markers``)."""
        return self.a, self.b


def take_mirrors(positions: Array, first: Array, neighbours: NDArray[np.int64],
                 predicted: Array | None = None) -> list[TakeMirror]:
    """The exchanges that give a labeling back its first frame's handedness (module doc), in
    the order they apply; arguments as ``take_exchange.take_exchanges``."""
    mates, _ = rigid_mates([positions], neighbours, PARTNERS)
    pairs = sorted({(min(a, int(b)), max(a, int(b))) for a in range(len(first)) for b in mates[a] if a in mates[b]})
    continued = positions if predicted is None else np.where(np.isfinite(positions), positions, predicted)
    working, done = np.stack([positions, continued]), []
    for _ in range(len(pairs)):
        flips = handedness_flips([working[0]], first, mates)[0]  # (F, N), the labels'
        firm = _clear_of_flat(working[0], flips, mates)
        flipped = np.nansum(flips, axis=0)  # a pair gains no more: most pairs have nothing to give back
        found = [m for a, b in pairs if firm[a] and firm[b] and flipped[a] + flipped[b] >= MIN_UNFLIPPED
                 and (m := _judged(working, first, mates, flips[:, [a, b]], a, b)) is not None]
        if not found:
            break
        best = max(found, key=lambda m: m.unflipped)
        moved = list(best.markers)
        working[:, best.start:best.stop, moved] = working[:, best.start:best.stop, moved[::-1]]
        done.append(best)
    return done


def _clear_of_flat(positions: Array, flips: Array, mates: NDArray[np.int64]) -> NDArray[np.bool_]:
    """``(N,)`` each marker's quadruple judged (clear of flat) in all but ``FLAT_SHARE`` of the
    frames labeling it: one flat more often is turned by the pose and says nothing of labels."""
    quads = np.column_stack([np.arange(len(mates)), mates])
    labeled = np.isfinite(positions[:, quads]).all(axis=(2, 3))  # (F, N)
    firm: NDArray[np.bool_] = (labeled & np.isnan(flips)).sum(axis=0) <= FLAT_SHARE * labeled.sum(axis=0)
    return firm


def _judged(tracks: Array, first: Array, mates: NDArray[np.int64], flips: Array, a: int, b: int) -> TakeMirror | None:
    """The pair's exchange over its best frames, None when it does not clear (module doc).
    ``tracks``: the labeled positions and the same continued over gaps by the prediction;
    ``flips``: ``(F, 2)`` the labels' flips of a's and b's quadruples. The exchange negates both
    sines, but the sine's scale (edges from the quadruple's first point) changes with it, and
    with it which frames are judged: the exchanged flips are computed, not derived."""
    labels = tracks[0]
    exchanged = labels.copy()
    exchanged[:, [a, b]] = labels[:, [b, a]]
    pair = np.stack([flips, handedness_flips([exchanged], first, mates, np.array([a, b]))[0]])  # (2, F, 2)
    both = np.asarray(np.isfinite(pair).all(axis=(0, 2)))  # each marker's quadruple judged in both labelings
    gain = np.where(both[:, None], pair[0] - pair[1], 0.0).sum(axis=1)
    if gain[1:][gain[1:] > 0].sum() < MIN_UNFLIPPED:  # no run can reach it: spare the search
        return None
    start, stop, unflipped = best_run(gain, may_exchange(labels[:, a], labels[:, b], tracks[1][:, a], tracks[1][:, b]))
    run = pair[:, start:stop][:, both[start:stop]]
    if unflipped < MIN_UNFLIPPED or mirrored_side(run.reshape(2, -1)) != 0:
        return None
    return TakeMirror(a, b, start, stop, unflipped)
