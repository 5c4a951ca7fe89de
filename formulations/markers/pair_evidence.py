"""Recovery of an exchanged pair by a whole window of shape evidence.

Two neighbours lost together come back; the window takes one reading of who is who, and if it
took the exchanged one, every later window inherits it: giving each track back costs a jump on
both paths. The exchange repair (``exchange``) undoes it at the template from one frame's
shape, and must ask for a large gain there, since one frame's skin motion and noise move a few
cm of markers by a few mm. A pair told apart by a small but steady difference (Hamner's
running take: radial and ulnar wrist markers 63 mm apart, 271 +- 4 and 259 +- 3 mm from the
elbow, the only rigid neighbour of either) never clears it; at 2 mm of noise they were
exchanged back and forth for 500 of 600 frames.

A window's solution holds many frames of such evidence. With the distance statistics of the
window's template (for a doubtful marker, those of when it was last trusted:
``IdentityCarry.forget_doubtful``), the shape log-likelihood of marker m at x in frame f is

    l_m(x, f) = - sum_j min(z_mj^2, CAP^2) / 2,   z_mj = (||x - r_j(f)|| - dbar_mj) / sd_mj,

over m's witnesses j seen in f: trusted neighbours (a doubtful one may hold anyone's point),
not the partner (their mutual distance is the same either way), rigid with m (learned sd under
``RIGID_SD_MM``, as the mirror repair's) once both have been seen for ``LEARNED_FRAMES`` (the
10 mm sd a first frame starts with is no shape learned). A marker across a joint is no
witness: its learned distance is a mean over the poses seen so far, and a new pose moves it by
more than its learned sd on every frame alike (Numediart's rolling take: the other leg's thigh
80 mm off a 40 mm sd exchanged two hand markers whose rigid neighbours all said no). The terms
are capped so that one slipped or mislabeled neighbour cannot decide alone. For a pair (a, b)
seen together in frames F, the log-likelihood ratio of the exchange is

    L(a, b) = sum_{f in F} l_a(x_b, f) + l_b(x_a, f) - l_a(x_a, f) - l_b(x_b, f).

The exchange may be older than the window (inherited at its template) or made inside it (one
of the pair back from an occlusion on the other's track, or both tracks stepping across), so
the sum runs from the frame f0 that makes it largest to the window's end, a change point
where such an exchange can begin (``_may_begin``: not between two smooth steps). The pair is
exchanged from f0 on where

- L exceeds ``EXCHANGE_NATS``;
- each of a's and b's own terms gains half of it: an exchange judged by one marker's
  witnesses alone is that marker's shape gone stale (a trochanter learned rigid with the
  pelvis while the hip kept still);
- the exchanged reading fits as a right label does, its mean capped z^2 at most ``FIT_Z2``,
  not merely the less bad of two misfits (a tennis shoulder at C7's point);

best pairs first, each marker in one pair at most. Only pairs with a doubtful label are judged
(below the service's 0.9 confidence at the template): the window's margins and the shape check
have already flagged an exchange that a re-acquisition made, and a label trusted by both is
left alone. And only pairs on one rigid segment (rigid with each other, as a witness is): two
segments' markers are told apart by their motion, and what one's witnesses say of the other's
point is weak (CMU 135_02 under the hard preset: the left and right toes, side by side, were
exchanged on the say of a shin and a knee learned rigid with the toes while the ankles kept
still). Frames are not independent evidence (skin motion is slow), so the bar is high: e^20, where a single
frame's noise gives a few nats.

Measured (lp-l1, 600 frames): seed-0 accuracy matrix 97.016 -> 97.104 %, swaps 1,721 ->
1,711, 8 of 85 rows higher and none lower (Vicon at 4 mm 88.73 -> 91.41 %, tennis with 30 %
deletions 94.10 -> 95.65 %); seeds 1-2 screen 98.753 -> 98.857 %, 11 of 80 rows higher, none
lower; the real takes unchanged; the hard preset (seeds 0-2, 400 frames, four takes) 92.08 ->
92.17 %, with one wrong exchange left (CMU 135_02 seed 0, 90.38 -> 89.50 %: a still subject's
toes, side by side, look rigid with each other); whole-length takes (seeds 0-1, default and
2 mm) HDM05 98.33 -> 99.73 % and 97.07 -> 98.84 % (a forefoot pair exchanged from frame 1646
to the end given back at 1691), CMU 135_02 97.09 -> 97.09 % and 95.08 -> 92.71 % (back-of-head
markers exchanged on the say of C7, which a neck kept still while the body turned made look
rigid with the head: 23 mm swept across, so no turning test on the learned pair stops it);
0.05-0.2 ms a frame on ``bench/markers_realtime.py``. The wrist case above is not reached:
exchanged at frame 83, before its distances are learned.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.lengths import lengths
from formulations.markers.mirror import RIGID_SD_MM, LearnedPairs
from formulations.markers.state import MarkerState
from formulations.markers.turns import taken_positions

CAP = 3.0  # z beyond 3 sd counts as 3: a slipped neighbour or a foreign point, not more evidence
# A pair's distance variance starts at a 100 mm^2 prior that decays by 0.97 a frame it is
# seen (``MarkerState.advance``): after 100 frames 5 mm^2 of it is left, so what is below
# ``RIGID_SD_MM``^2 then was learned (both markers' motion sample counts bound the pair's).
LEARNED_FRAMES = 100
EXCHANGE_NATS = 20.0  # the whole window's log-likelihood ratio an exchange must clear (module doc)
FIT_Z2 = 2.0  # the exchanged reading's mean capped z^2: a right label's is about 1


def repair_pair_evidence(
    state: MarkerState, frames: list[np.ndarray], taken: np.ndarray, doubtful: np.ndarray,
) -> tuple[np.ndarray, int]:
    """``taken`` (``(N, M)`` point per marker and frame, -1 none) with exchanged pairs given
    back over the whole window (module doc), and how many pairs.

    Args:
        state: The marker state at the window's template (its distance statistics judge).
        frames: The window's points per frame after the template.
        taken: The window's labels.
        doubtful: ``(N,)`` markers whose label at the template is doubtful.
    """
    pairs = _judged_pairs(state, doubtful)
    if len(pairs) == 0 or taken.shape[1] == 0:
        return taken, 0
    where = _positions(frames, taken)  # (M, N, 3)
    # Only trusted neighbours testify: doubtful ones may hold anyone's point.
    ratio, onset = _exchange_ratio(state, np.where(doubtful[None, :, None], np.nan, where), where, pairs)
    taken, used, count = taken.copy(), np.zeros(len(taken), bool), 0
    for p in np.argsort(-ratio):
        a, b = pairs[p]
        if ratio[p] <= EXCHANGE_NATS:
            break
        if used[a] or used[b]:
            continue
        taken[[a, b], onset[p]:] = taken[[b, a], onset[p]:]
        used[[a, b]], count = True, count + 1
    return taken, count


def _judged_pairs(state: MarkerState, doubtful: np.ndarray) -> np.ndarray:
    """``(P, 2)`` each doubtful marker with each neighbour rigid with it (learned, as a
    witness is: ``_log_shape``), once per pair."""
    rows = np.flatnonzero(doubtful)
    pairs = np.column_stack([np.repeat(rows, state.neighbours.shape[1]), state.neighbours[rows].ravel()])
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    pairs = pairs[_rigid(state, pairs[:, 0], pairs[:, 1], LearnedPairs.of(state).var[pairs[:, 0], pairs[:, 1]])]
    return np.unique(np.sort(pairs, axis=1), axis=0) if len(pairs) else pairs.reshape(0, 2)


def _positions(frames: list[np.ndarray], taken: np.ndarray) -> np.ndarray:
    """``(M, N, 3)`` each marker's labeled point per frame, NaN where it has none."""
    return np.stack([taken_positions(points, taken[:, f]) for f, points in enumerate(frames)])


def _exchange_ratio(
    state: MarkerState, witnesses: np.ndarray, where: np.ndarray, pairs: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``(P,)`` L(a, b) of the module doc from its change point, -inf for a pair never seen
    together after it or failing the two checks (module doc); and ``(P,)`` the change point
    f0 (a frame of the window). ``where``, ``witnesses``: ``(M, N, 3)`` every marker's point,
    and the neighbours' that may testify."""
    a, b = pairs[:, 0], pairs[:, 1]
    together = np.isfinite(where[:, a, 0]) & np.isfinite(where[:, b, 0])  # (M, P)
    xa, xb = where[:, a], where[:, b]
    # each marker judged at the other's point and at its own, its witnesses gathered once
    (a_at_b, a_at_a), (a_terms, _) = _log_shape(state, witnesses, a, np.stack([xb, xa]), b)
    (b_at_a, b_at_b), (b_terms, _) = _log_shape(state, witnesses, b, np.stack([xa, xb]), a)
    side_a, side_b = a_at_b - a_at_a, b_at_a - b_at_b

    def from_frame(per_frame: np.ndarray) -> np.ndarray:  # (M, P): sum over f >= f0
        summed: np.ndarray = np.cumsum(np.where(together, per_frame, 0.0)[::-1], axis=0)[::-1]
        return summed

    total = from_frame(side_a + side_b)
    onset = np.argmax(np.where(together & _may_begin(xa, xb), total, -np.inf), axis=0)
    at = (onset, np.arange(len(pairs)))
    terms = from_frame(a_terms + b_terms)[at]
    misfit = -2.0 * from_frame(a_at_b + b_at_a)[at] / np.maximum(terms, 1)  # mean capped z^2, exchanged
    agreed = (from_frame(side_a)[at] > EXCHANGE_NATS / 2) & (from_frame(side_b)[at] > EXCHANGE_NATS / 2)
    judged = together.any(axis=0) & agreed & (misfit <= FIT_Z2)
    return np.where(judged, total[at], -np.inf), onset


def _may_begin(xa: np.ndarray, xb: np.ndarray) -> np.ndarray:
    """``(M, P)`` frames where an exchange of the pair may begin: the window's first (it was
    inherited), one after either was unseen (it came back on the other's track), or where
    the labels step farther than the exchanged ones would (the window made it there).
    Elsewhere an exchange would put a jump into two smooth tracks."""
    steps = lengths(xa[1:] - xa[:-1]) + lengths(xb[1:] - xb[:-1])
    crossed = lengths(xb[1:] - xa[:-1]) + lengths(xa[1:] - xb[:-1])
    smooth = np.isfinite(steps) & (steps < crossed)
    first = np.ones((1,) + steps.shape[1:], bool)
    may: np.ndarray = np.concatenate([first, ~smooth])
    return may


def _log_shape(
    state: MarkerState, witnesses: np.ndarray, m: np.ndarray, x: np.ndarray, partner: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``(..., M, P)`` l_m(x, f) of the module doc for ``x`` ``(..., M, P, 3)``, the partner's
    distance left out, and ``(..., M, P)`` how many neighbours testified."""
    neighbours = state.neighbours[m]  # (P, K)
    distance = lengths(x[..., None, :] - witnesses[:, neighbours])  # (..., M, P, K)
    z = (distance - state.distance_mean[m]) / np.sqrt(np.maximum(state.distance_var[m], 1.0))
    rigid = _rigid(state, m[:, None], neighbours, state.distance_var[m])  # (P, K)
    counted = np.isfinite(z) & (neighbours != partner[:, None]) & rigid
    log_f: np.ndarray = -0.5 * np.where(counted, np.minimum(z**2, CAP**2), 0.0).sum(axis=-1)
    return log_f, counted.sum(axis=-1)


def _rigid(state: MarkerState, m: np.ndarray, j: np.ndarray, var: np.ndarray) -> np.ndarray:
    """Markers ``m`` and ``j`` (broadcast) rigid with each other: their distance variance
    ``var`` under ``RIGID_SD_MM``^2, learned over ``LEARNED_FRAMES`` of both."""
    learned = np.minimum(state.motion_samples[m], state.motion_samples[j]) >= LEARNED_FRAMES
    rigid: np.ndarray = learned & (var < RIGID_SD_MM**2)
    return rigid
