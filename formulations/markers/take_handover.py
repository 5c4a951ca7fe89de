"""Recovery over a whole labeled take: a track taken over by another marker, given back to the
marker whose track it continues.

A window that reads a marker as occluded from frame t on, while another marker takes the
very point its track runs into, has handed the track over. The window's costs can prefer
that: a seen marker's expected step is its own last step, one difference of two noisy points,
while an occluded marker's is its neighbours' fitted motion, so along the same points the
occluded marker's path is cheaper (OpenSim walking5 at 2 mm: the left lateral condyle, lost
for 140 frames, took the left thigh marker's last 10 frames at 46 nats against 52, and the
thigh marker was read as occluded while its point sat 3 mm from where it was heading). Once
the take is labeled both tracks are known, and the hand-over shows as two jumps:

- the owner V, labeled in frame t - 1 and not in t, was heading to h_V(t) (its last labeled
  step continued, ``heading``); the taker T's point x in t lies within ``CONTINUE_SDS``
  sd of it: |x - h_V(t)| <= 3.4 s_V, s_V the per-axis sd of V's own constant-velocity
  residual x_t - 2 x_(t-1) + x_(t-2) over the take (MAD-scaled median: 99 % of a 3D
  Gaussian's norms lie within 3.37 sd);
- T arrives from elsewhere: unlabeled in t - 1 or jumping, x lies outside T's own 3.4 s_T
  of where T was heading (its labels continued by the windows' fill), and ``FAR_RATIO``
  times farther from it than from h_V(t).

Where both were lost (V unlabeled in t - 1 too, T coming back in t) neither heading is sure:
a returning marker's prediction has drifted (walking5 at 4 mm: the heel came back 101 mm from
its own prediction and 22 mm from the lost malleolus's, which took its point for 33 frames).
Then only the first frame judges, and only a near pair (T among V's ``NEAR`` first-frame
neighbours): the points must cost the taker, against its witnesses, ``CLAIM_NATS`` more than
the owner over the frames both have witnesses seen, at least ``MIN_RATE`` a frame, and twice
the owner's mean (``FirstShape.claims``); and the owner's witnesses must fit its own labels
outside the run as right labels do, or they are no judge of the run.

Unless the windows, once both are seen, read the track as the taker's: the run ends with the
owner seen again, the taker's labels go on along the run's track for ``GOES_ON_FRAMES``
(each within the taker's own 3.4 s_T of where it was heading), and over those frames the two
fit the first frame no better exchanged (``FirstShape.exchanged``). On CMU 85_02 under the
hard preset (seed 0) the claim gave RTOE's 82 frames to RMT5 on the ankle marker alone (163
mm from the point, against 183 mm to RTOE and 151 mm to RMT5 in the first frame: the ankle
turns between the shank and the foot), while at the run's end RMT5 was seen on its own point
and RTOE went on along the track: 99.31 % right against nn-hungarian's 99.97 %. A taker that
leaves the track within those frames was exchanged with the owner for a frame or two as both
came back (the racing take's elbow and forearm clusters at 2 mm); one that stays on it while
the pair fits better exchanged was exchanged by the windows (the tennis serve's two left wrist
markers with ghosts, the racing take's arm cluster with deletions): in both the claim was
right, and it stands. Accuracy matrix (lp-l1, 600 frames, five conditions): seed 0 one row
up (Hamner with deletions 99.84 -> 99.99 %), seeds 1-2 of four takes 4 up (03_rolling, +0.06
to +0.13), none down; under the hard preset 03_rolling seed 2 lost 0.68 points, though the
claim dropped there was wrong: the first pass's labels change what the second pass starts from.

Then T's labels from t, while T stays labeled and V does not, are V's: V gets them back, and
T is occluded there (its fill held where it last was; the take's rigid fill refills it from
donors). Earliest first, each judged on the labels the ones before left.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.heading import track_heading
from formulations.markers.lengths import lengths
from formulations.markers.noise import MAD_TO_SIGMA
from formulations.markers.take_exchange import EXCHANGE_NATS, FIT_COST, MIN_RATE, capped_cost, near_pairs, rigid_pairs

Array = NDArray[np.float64]

CONTINUE_SDS = 3.4  # the 99 % radius of a 3D Gaussian, in per-axis sds
FAR_RATIO = 3.0  # how much farther the taker's own heading must be than the owner's
MIN_RESIDUALS = 10  # constant-velocity residuals (frames) a marker needs for its step sd
NEAR = 6  # a returning marker takes a lost neighbour's point: one among its six nearest
CLAIM_NATS = EXCHANGE_NATS  # as the exchange: frames are not independent (skin motion is slow)
GOES_ON_FRAMES = 10  # frames the taker must go on along the track once the owner is seen: not a one-frame exchange


@dataclass(frozen=True)
class Handover:
    """Marker ``owner``'s track, held by ``taker`` over frames [start, stop), given back."""

    owner: int
    taker: int
    start: int
    stop: int


def take_handovers(
    positions: Array, first: Array, neighbours: NDArray[np.int64], predicted: Array | None = None,
) -> list[Handover]:
    """The hand-overs of a labeling (module doc), in the order they apply.

    Args:
        positions: ``(F, N, 3)`` labeled positions, NaN where a marker has no label.
        first: ``(N, 3)`` the labeled first frame (NaN for a marker it lacks).
        neighbours: ``(N, K)`` each marker's neighbours (``MarkerState.neighbours``).
        predicted: ``(F, N, 3)`` the windows' fill where a marker has no label (NaN
            elsewhere); without it an unlabeled marker is where it was last labeled.
    """
    working = positions.copy()
    fill = np.full_like(positions, np.nan) if predicted is None else predicted.copy()
    scale = step_sd(positions)
    shape = FirstShape(*rigid_pairs(positions, first, neighbours), np.linalg.norm(first[:, None] - first[None], axis=2))
    near = near_pairs(neighbours, NEAR)
    headings = _Headings(working, fill, range(positions.shape[1]))
    done: list[Handover] = []
    for _ in range(positions.shape[0] * positions.shape[1]):
        # One sweep: the frames before a hand-over's start kept their labels and were judged.
        found = _first_handover(working, fill, headings, scale, shape, near, done[-1].start if done else 1)
        if found is None:
            break
        hand_back(working, fill, found)
        headings.update(working, fill, (found.owner, found.taker))
        done.append(found)
    return done


def hand_back(positions: Array, fill: Array, handover: Handover) -> None:
    """Undo ``handover`` in place: the owner takes the taker's labels over its run, and the
    taker is unlabeled there with its fill held (``held_fill``)."""
    run, held = slice(handover.start, handover.stop), held_fill(positions, fill, handover)
    positions[run, handover.owner], fill[run, handover.owner] = positions[run, handover.taker], np.nan
    positions[run, handover.taker], fill[run, handover.taker] = np.nan, held


def held_fill(positions: Array, fill: Array, handover: Handover) -> Array:
    """``(3,)`` where the taker is held while occluded over the hand-over: its fill in the frame
    before, else its label there (it jumped from its own track)."""
    before = fill[handover.start - 1, handover.taker]
    held: Array = (before if np.isfinite(before).all() else positions[handover.start - 1, handover.taker]).copy()
    return held


def step_sd(positions: Array) -> Array:
    """``(N,)`` per-axis sd of each marker's constant-velocity residual over its labeled
    frames (MAD-scaled median of the absolute residuals); NaN with too few."""
    residual = positions[2:] - 2 * positions[1:-1] + positions[:-2]  # (F - 2, N, 3)
    known: NDArray[np.bool_] = np.asarray(np.isfinite(residual).all(axis=2), dtype=bool)
    absolute = np.where(known[..., None], np.abs(residual), np.nan).transpose(1, 0, 2).reshape(positions.shape[1], -1)
    sd = np.full(positions.shape[1], np.nan)
    enough = known.sum(axis=0) >= MIN_RESIDUALS
    if enough.any():
        sd[enough] = MAD_TO_SIGMA * np.nanmedian(absolute[enough], axis=1)
    return sd


class _Headings:
    """Where each marker was heading in each frame (``(F, N, 3)``): ``owner`` from its labels
    alone, ``taker`` from its labels continued by the fill; a hand-over changes two markers'."""

    def __init__(self, positions: Array, fill: Array, markers: Iterable[int]) -> None:
        self.owner, self.taker = np.empty_like(positions), np.empty_like(positions)
        self.update(positions, fill, markers)

    def update(self, positions: Array, fill: Array, markers: Iterable[int]) -> None:
        """Recompute the headings of ``markers`` from ``positions`` and ``fill`` as they are now."""
        for n in markers:
            self.owner[:, n] = track_heading(positions[:, n])
            labeled: NDArray[np.bool_] = np.asarray(np.isfinite(positions[:, n]).all(axis=1), dtype=bool)
            self.taker[:, n] = track_heading(np.where(labeled[:, None], positions[:, n], fill[:, n]))


def _first_handover(
    positions: Array, fill: Array, headings: _Headings, scale: Array, shape: FirstShape, near: NDArray[np.bool_],
    after: int,
) -> Handover | None:
    """The earliest hand-over the labels show from frame ``after`` on (module doc), None when there is none."""
    labeled: NDArray[np.bool_] = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)  # (F, N)
    owner_heading, taker_heading = headings.owner, headings.taker
    gate = CONTINUE_SDS * scale  # (N,)
    own_miss = lengths(positions - taker_heading)  # (F, N): each label from its own heading
    arrives = labeled[1:] & (~labeled[:-1] | ~(own_miss[1:] <= gate))  # (F - 1, N): T from frame t = 1..
    leaves = labeled[:-1] & ~labeled[1:]  # V labeled in t - 1, not in t
    returns, lost = labeled[1:] & ~labeled[:-1], ~labeled[:-1] & ~labeled[1:]
    candidates = np.flatnonzero(arrives.any(axis=1) & (leaves.any(axis=1) | lost.any(axis=1))) + 1
    for t0 in (int(t) for t in candidates[candidates >= after]):
        owners, takers = np.flatnonzero(leaves[t0 - 1]), np.flatnonzero(arrives[t0 - 1])
        x = positions[t0, takers]  # (T, 3)
        to_owner = lengths(x[:, None] - owner_heading[t0, owners][None])  # (T, V)
        to_own = np.nan_to_num(own_miss[t0, takers], nan=np.inf)[:, None]
        fits = (to_owner <= gate[owners][None]) & (to_own > FAR_RATIO * to_owner) & ~(to_own <= gate[takers][:, None])
        order = np.argsort(np.where(fits, to_owner / gate[owners][None], np.inf), axis=None)[: int(fits.sum())]
        for k, v in zip(*np.unravel_index(order, fits.shape)):
            found = _handed(labeled, int(owners[v]), int(takers[k]), t0)
            if shape.allows(positions, found.owner, found.taker, t0, found.stop):
                return found
        for taker in np.flatnonzero(returns[t0 - 1]):
            for owner in np.flatnonzero(lost[t0 - 1] & near[taker]):
                found = _handed(labeled, int(owner), int(taker), t0)
                # the stand-down only where a claim is made: most candidate pairs make none
                if shape.claims(positions, found.owner, found.taker, t0, found.stop) and not _windows_keep_taker(
                    positions, own_miss, gate, shape, found,
                ):
                    return found
    return None


def _windows_keep_taker(positions: Array, own_miss: Array, gate: Array, shape: FirstShape, handover: Handover) -> bool:
    """Whether the windows, with both markers seen, read the run's track as the taker's (module
    doc): from the frame the run ends (the owner seen again) the taker's labels go on along it,
    each within its own gate of where it was heading, for ``GOES_ON_FRAMES``, and the two fit
    the first frame no better exchanged there."""
    stop, after = handover.stop, slice(handover.stop, handover.stop + GOES_ON_FRAMES)
    goes_on = stop < len(own_miss) and bool((own_miss[after, handover.taker] <= gate[handover.taker]).all())
    return goes_on and not shape.exchanged(positions, handover.owner, handover.taker, after.start, after.stop)


def _handed(labeled: NDArray[np.bool_], owner: int, taker: int, start: int) -> Handover:
    """The hand-over from ``start`` while the taker stays labeled and the owner does not."""
    after = labeled[start:, taker] & ~labeled[start:, owner]
    return Handover(owner, taker, start, start + (int(np.argmin(after)) if not after.all() else len(after)))


@dataclass(frozen=True)
class FirstShape:
    """The first frame's say on whose points a run is (module doc): ``spread`` and ``rigid``
    as ``take_exchange.rigid_pairs``, ``d0`` the first frame's distances."""

    spread: Array
    rigid: NDArray[np.bool_]
    d0: Array

    def allows(self, positions: Array, owner: int, taker: int, start: int, stop: int) -> bool:
        """Whether the taker's points over [start, stop) may be the owner's: where both have
        witnesses seen, they fit the owner (mean cost at most ``FIT_COST``) at no more cost in
        sum than the taker; where only one has, they fit the owner or misfit the taker."""
        as_owner, as_taker, both = self._costs(positions, owner, taker, start, stop)
        if both.any():
            return bool(as_owner[both].sum() <= as_taker[both].sum() and as_owner[both].mean() <= FIT_COST)
        if np.isfinite(as_owner).any():
            return bool(np.nanmean(as_owner) <= FIT_COST)
        return not np.isfinite(as_taker).any() or bool(np.nanmean(as_taker) > FIT_COST)

    def claims(self, positions: Array, owner: int, taker: int, start: int, stop: int) -> bool:
        """Whether the taker's points over [start, stop) are the owner's on the first frame's
        say alone (module doc: both lost)."""
        as_owner, as_taker, both = self._costs(positions, owner, taker, start, stop)
        gain = float((as_taker[both] - as_owner[both]).sum())
        return bool(both.any() and gain >= max(CLAIM_NATS, MIN_RATE * both.sum())
                    and as_taker[both].mean() >= 2.0 * as_owner[both].mean()
                    and self._kept_elsewhere(positions, owner, (owner, taker), start, stop))

    def _kept_elsewhere(self, positions: Array, m: int, pair: tuple[int, int], start: int, stop: int) -> bool:
        """Whether marker m's own labels outside [start, stop) (frame 0 aside) fit its witnesses
        (mean cost at most ``FIT_COST``), as ``take_exchange`` asks of a pair outside its run.
        A claim's evidence is how well the points fit the owner's witnesses, and witnesses that
        do not keep the first frame where the owner is labeled give none: the basket sprint's
        ear (30 % deletions, seed 0) had as "rigid" the forearm and the elbow, still while it
        was labeled, fitting its own labels at 3.8-4.1 of 4.5, and the claims gave the temple's
        returns to it, 104 frames wrong. Not asked of the taker: it is often wrong elsewhere
        too (the racing take's left glove with deletions: the taker, on the owner's point later
        as well, fits its own labels at 1.45, and the claim was right)."""
        cost = self._cost(positions, m, positions[:, m], 0, pair)
        cost[start:stop], cost[0] = np.nan, np.nan
        return not np.isfinite(cost).any() or bool(np.nanmean(cost) <= FIT_COST)

    def exchanged(self, positions: Array, a: int, b: int, start: int, stop: int) -> bool:
        """Whether markers a and b over [start, stop) fit the first frame better each on the
        other's points (summed over the frames where all four costs are known)."""
        b_as_a, b_as_b, b_known = self._costs(positions, a, b, start, stop)
        a_as_b, a_as_a, a_known = self._costs(positions, b, a, start, stop)
        known = a_known & b_known
        return bool(known.any() and (b_as_a + a_as_b)[known].sum() < (a_as_a + b_as_b)[known].sum())

    def _costs(self, positions: Array, owner: int, taker: int, start: int, stop: int) -> tuple[Array, Array, NDArray[np.bool_]]:
        """The taker's points over [start, stop) costed as the owner's and as its own (``_cost``),
        and the frames where both have witnesses seen."""
        x = positions[start:stop, taker]
        as_owner, as_taker = (self._cost(positions, m, x, start, (owner, taker)) for m in (owner, taker))
        return as_owner, as_taker, np.isfinite(as_owner) & np.isfinite(as_taker)

    def _cost(self, positions: Array, m: int, x: Array, start: int, pair: tuple[int, int]) -> Array:
        """``(L,)`` mean capped z^2 / 2 of the points ``x`` against marker m's first-frame
        distances to its rigid witnesses (``take_exchange.capped_cost``); NaN with none seen."""
        j = np.flatnonzero(self.rigid[m])
        j = j[(j != pair[0]) & (j != pair[1])]
        if not j.size:
            return np.full(len(x), np.nan)
        witnesses = positions[start : start + len(x)][:, j]
        # d0 is one noisy frame: d - d0 varies by the spread twice (+ 1 mm^2 for a spread near 0)
        z = (lengths(x[:, None] - witnesses) - self.d0[m, j]) / np.sqrt(2.0 * self.spread[m, j] + 1.0)
        return capped_cost(z)
