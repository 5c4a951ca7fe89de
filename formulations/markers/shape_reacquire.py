"""Where to look for a marker whose prediction has lost it: the free point its shape fits.

A marker occluded while its limb moved fast (a tennis serve at 50 Hz) may be predicted
far from where it is: it followed the neighbours seen at its last sighting, and when the
rigid ones were lost with it only loose ones (the trunk) were left. Its gate never reaches
its point again, and the error lasts to the end of the take. Its learned distances to the
rigid neighbours seen now still say where it is (Ringer & Lasenby 2004: markers on one
segment keep their distances). For a marker unseen ``after`` frames or more, each free
point p (no seen marker's prediction within ``claim_mm``) is scored against its ``rigid``
most rigid neighbours k seen now, by

    chi2(p) = sum_k (||p - x_k|| - dbar_nk)^2 / (var_nk + noise_var),

and the markers are matched to the free points by ``linear_sum_assignment`` on chi2. A
marker moves to its point only when chi2 is inside the chi-square ``quantile`` gate, every
other free point is outside it (a mirror image or a lost neighbour's point must not be
taken on a coin toss), the point is not another unseen marker's (predicted within
``claim_mm`` of it and inside that marker's own gate), and its current prediction fits
worse. Four neighbours at the 0.999 quantile: a point within about 3 sd of all four learned
distances.

The claim of other unseen markers matters for pairs a few cm apart on one segment (wrist
radius and ulna): distances to farther neighbours barely tell the two points apart, and
with noisy data the "rigid" judges include markers across a joint. On HDM05 at 4 mm noise
(seed 0) LWRB, unseen 9 frames, was moved onto LWRA's point as LWRA reappeared 20 mm from
its own prediction; the two stayed exchanged for 230 frames (97.2 % -> 99.98 % with the claim).
A prediction near the point is not enough to claim it: on 03_rolling at 4 mm the stale
predictions of markers lost for long lay near the points of others coming back, and claims
by prediction alone blocked re-acquisitions that were right (82.4 -> 72.9 %). Accuracy
matrix, seed 0, 600 frames, five conditions, lp-l1: 96.23 -> 96.26 % mean, swaps 2,477 ->
2,439 (hdm05 at 4 mm +2.8 points, wheelchair racing at 4 mm +0.9, 03_rolling with ghosts
-1.0); the 80-row screen of seeds 1-2 98.63 % either way, swaps 686 -> 680.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.stats import chi2 as chi_square

from formulations.markers.lengths import lengths
from formulations.markers.reacquire import free_points
from formulations.markers.state import MarkerState


@dataclass(frozen=True)
class ShapeReacquisition:
    """When a lost marker's prediction moves to the free point its shape fits.

    Attributes:
        after: Frames unseen before a marker is looked for by its shape.
        rigid: Neighbours, the most rigid seen now, that judge a point (at most).
        min_rigid: Fewer rigid neighbours seen than this, and the marker is not looked for
            (two distances leave a circle, but the free points on it are few).
        max_sd_mm: A neighbour whose distance varies more than this is not rigid with the
            marker (skin markers on one segment keep their distances within a few mm).
        noise_var_mm2: Added to each learned distance variance: the noise of two points.
        quantile: Chi-square quantile of the gate.
        claim_mm: Points this close to a seen marker's prediction are that marker's.
    """

    after: int = 3
    rigid: int = 4
    min_rigid: int = 2
    max_sd_mm: float = 10.0
    noise_var_mm2: float = 4.0
    quantile: float = 0.999
    claim_mm: float = 30.0


SHAPE_REACQUISITION = ShapeReacquisition()


def reacquire_by_shape(
    guess: np.ndarray, state: MarkerState, points: np.ndarray, settings: ShapeReacquisition = SHAPE_REACQUISITION,
) -> np.ndarray:
    """``(N, 3)`` predictions, a lost marker's moved onto the free point its shape fits."""
    looked_for = np.flatnonzero(state.unseen >= settings.after)
    if len(looked_for) == 0 or len(points) == 0:
        return guess
    judges = _judges(state, looked_for, settings)
    kept = judges.count >= settings.min_rigid
    looked_for, judges = looked_for[kept], judges.subset(kept)
    free = free_points(points, guess[state.visible], settings.claim_mm) if len(looked_for) else points[:0]
    if len(free) == 0:
        return guess
    score = judges.chi_square(guess, np.vstack([free, guess[looked_for]]))
    own = score[np.arange(len(looked_for)), len(free) + np.arange(len(looked_for))]  # each prediction's own fit
    score = score[:, : len(free)]
    inside = score <= chi_square_gate(settings.quantile, settings.rigid)[judges.count][:, None]
    if not inside.any():  # no point fits any lost marker's shape: nothing can move (most frames)
        return guess
    outside = (min(score.shape) + 1) * (score.max() + 1.0)  # above any sum of inside scores
    rows, cols = linear_sum_assignment(np.where(inside, score, outside))
    alone = inside[rows, cols] & (inside.sum(axis=1)[rows] == 1) & (inside.sum(axis=0)[cols] == 1)
    better = alone & (score[rows, cols] < own[rows])
    rows, cols = rows[better], cols[better]
    if not len(rows):  # asked only now: whether another lost marker claims the point costs the most
        return guess
    contested = _claimed_by_another(guess, state, looked_for, free, settings)[rows, cols]
    moved = guess.copy()
    moved[looked_for[rows[~contested]]] = free[cols[~contested]]
    return moved


@lru_cache(maxsize=8)
def chi_square_gate(quantile: float, most: int) -> np.ndarray:
    """``(most + 1,)`` the chi-square ``quantile`` for 0..``most`` degrees of freedom (NaN at 0),
    looked up per judged marker: scipy's ``ppf`` costs more per call than the rest of a frame's
    re-acquisition test, and the judges are at most ``ShapeReacquisition.rigid``."""
    gate: np.ndarray = chi_square.ppf(quantile, np.arange(most + 1))
    gate.setflags(write=False)
    return gate


def _claimed_by_another(
    guess: np.ndarray, state: MarkerState, looked_for: np.ndarray, free: np.ndarray, settings: ShapeReacquisition,
) -> np.ndarray:
    """``(L, P)`` the free point is the claim of another unseen marker (``point_claims``)."""
    claims = point_claims(guess, state, free, settings)
    by_others: np.ndarray = (claims.sum(axis=0)[None] - claims[looked_for]) > 0
    return by_others


def point_claims(
    guess: np.ndarray, state: MarkerState, free: np.ndarray, settings: ShapeReacquisition = SHAPE_REACQUISITION,
) -> np.ndarray:
    """``(N, P)`` unseen marker n claims free point p: it is predicted (``guess``) within
    ``claim_mm`` of p, and p is inside its own chi-square gate (at least one rigid neighbour seen)."""
    unseen = np.flatnonzero(~state.visible)
    near = lengths(free[None] - guess[unseen][:, None]) <= settings.claim_mm  # (U, P)
    claims = np.zeros((len(state.visible), len(free)), bool)
    close = np.flatnonzero(near.any(axis=1))
    if len(close):
        judges = _judges(state, unseen[close], settings)
        gate = chi_square_gate(settings.quantile, settings.rigid)[np.maximum(judges.count, 1)][:, None]
        fits = (judges.chi_square(guess, free) <= gate) & (judges.count >= 1)[:, None]
        claims[unseen[close]] = near[close] & fits
    return claims


@dataclass(frozen=True)
class _Judges:
    """Per looked-for marker, the rigid neighbours seen now that judge a point."""

    neighbour: np.ndarray  # (L, R) marker index
    counted: np.ndarray  # (L, R) a rigid neighbour seen now (False pads)
    mean: np.ndarray  # (L, R) learned distance, mm
    spread: np.ndarray  # (L, R) its variance plus the noise of two points, mm^2

    @property
    def count(self) -> np.ndarray:
        count: np.ndarray = self.counted.sum(axis=1)
        return count

    def subset(self, keep: np.ndarray) -> _Judges:
        return _Judges(self.neighbour[keep], self.counted[keep], self.mean[keep], self.spread[keep])

    def chi_square(self, guess: np.ndarray, points: np.ndarray) -> np.ndarray:
        """``(L, P)`` chi2 of every point for each marker (module doc)."""
        distance = lengths(points[None, :, None] - guess[self.neighbour][:, None])  # (L, P, R)
        score: np.ndarray = (self.counted[:, None] * (distance - self.mean[:, None]) ** 2 / self.spread[:, None]).sum(axis=2)
        return score


def _judges(state: MarkerState, markers: np.ndarray, settings: ShapeReacquisition) -> _Judges:
    """The ``rigid`` most rigid neighbours of each marker among those seen now with sd <= ``max_sd_mm``."""
    var = state.distance_var[markers]
    usable = state.visible[state.neighbours[markers]] & (var <= settings.max_sd_mm**2)
    order = np.argsort(np.where(usable, var, np.inf), axis=1)[:, : settings.rigid]
    rows, picked = np.arange(len(markers))[:, None], (markers[:, None], order)
    return _Judges(state.neighbours[picked], usable[rows, order], state.distance_mean[picked],
                   var[rows, order] + settings.noise_var_mm2)
