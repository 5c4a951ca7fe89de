"""Witnesses of a pair by the difference of its distances to them, for a pair that no marker
is rigid with.

The take-wide exchange (``take_exchange``) judges a pair (a, b) by the markers rigid with both.
A segment with two markers left has none: the wheelchair basketball sprint's head, whose
forehead marker is absent from the start, keeps only its temple and ear marker, 78 mm apart;
lost together for 75 frames under 30 % deletions, they come back exchanged and stay so for
115 frames (seed 0), and nothing rigid says which is which. Yet the difference of their
distances to a marker j,

    D_j(t) = ||x_a(t) - r_j(t)|| - ||x_b(t) - r_j(t)||,

keeps its sign and roughly its size where each distance does not: the temple sits 45-75 mm
farther than the ear from C7, the scapula and the acromion however the neck bends. An
exchange flips D_j. So j witnesses the pair when |D_j| varies little over the take (its
deciles' span, ``take_spread.decile_spread``, as a distance's; |D_j|, so that an exchanged
stretch does not widen it): s_j <= ``RIGID_SD_MM``, and when the first frame's D0_j is at
least ``CAP`` of those from zero: the exchanged reading, -D_j, then lies 2 ``CAP`` s_j from
the right one. The labels then cost, per frame and witness, min(z^2, CAP^2) / 2 with
z = (D_j - D0_j) / s_j, exchanged z = (-D_j - D0_j) / s_j, as ``take_exchange`` prices its
witnesses.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.state import RIGID_SD_MM
from formulations.markers.take_spread import decile_spread

Array = NDArray[np.float64]

CAP = 3.0  # as take_exchange.CAP: the first frame's difference must clear the cap


def difference_witnesses(positions: Array, a: int, b: int, candidates: NDArray[np.int64], d0: Array,
                         ) -> tuple[Array, Array, Array] | None:
    """``(F, W)`` D_j of the pair (a, b) to each witness (NaN where a, b or j is unlabeled),
    ``(W,)`` the first frame's D0_j, and ``(W,)`` s_j; None when no candidate witnesses.

    Args:
        positions: ``(F, N, 3)`` labeled positions, NaN where a marker has no label.
        candidates: Markers to try (the pair's neighbours); the pair itself is left out.
        d0: ``(N, N)`` the labeled first frame's distances (NaN for a marker it lacks).
    """
    j = np.setdiff1d(candidates, [a, b])
    j = j[np.isfinite(d0[a, j]) & np.isfinite(d0[b, j])]
    if not j.size:
        return None
    apart = (np.linalg.norm(positions[:, a, None] - positions[:, j], axis=2)
             - np.linalg.norm(positions[:, b, None] - positions[:, j], axis=2))
    sd = np.sqrt(decile_spread(np.abs(apart).T))  # NaN with too few frames: compares False below
    apart0 = d0[a, j] - d0[b, j]
    typical = typical_size(apart)
    kept = (sd <= RIGID_SD_MM) & (np.abs(apart0) >= CAP * sd) & (np.abs(np.abs(apart0) - typical) <= CAP * sd)
    if not kept.any():
        return None
    return apart[:, kept], apart0[kept], sd[kept]


def fit_spread(apart: Array, apart0: Array, sd: Array) -> Array:
    """``(W,)`` the spread a fit by these witnesses is held to (``take_exchange``'s fit, not
    its gain): s_j widened by how far the first frame's |D0_j| lies from the take's median
    |D_j| (exchange-blind, as |D_j| is; at most ``CAP`` s_j for a witness kept). A pair no
    marker is rigid with is judged across a joint, and a pose the first frame did not have
    moves D_j as a whole: the basket sprint's head under 30 % deletions (seed 0) differs by 51 mm
    in its distances to one witness against 72 in the first frame (s_j 9.7), so its right labels fit
    at 1.8, over ``take_exchange.FIT_COST``, and the exchanged stretch (frames 108-577) stayed.
    """
    widened: Array = np.sqrt(sd**2 + np.nan_to_num(np.abs(apart0) - typical_size(apart)) ** 2)
    return widened


def typical_size(apart: Array) -> Array:
    """``(W,)`` the take's median |D_j|, which an exchanged stretch leaves as it was (NaN for a
    witness never labeled with the pair)."""
    typical: Array = np.full(apart.shape[1], np.nan)
    labeled = np.isfinite(apart).any(axis=0)  # nanmedian warns on a column of NaN
    typical[labeled] = np.nanmedian(np.abs(apart[:, labeled]), axis=0)
    return typical


def pair_offset(own: Array, other: Array, d0: float, spread: float) -> Array:
    """``(F, 1)`` the pair's distance off the first frame's, in sqrt(2) take sds (``spread``:
    its variance, mm^2; the first frame's distance is as noisy as any other's), NaN where
    either is unlabeled. An exchange of the two keeps their distance: labels that moved onto
    other markers' points do not (the tennis serve's first pass, 2026-12-07: its forearm and
    wrist labels RFRM and RWRB on the elbow's and the upper arm's points from frame 209, 135 mm
    apart against 125, which the difference witnesses alone exchanged).
    """
    offset: Array = (np.linalg.norm(own - other, axis=1) - d0) / np.sqrt(2.0 * spread)
    return offset[:, None]
