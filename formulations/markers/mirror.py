"""Recovery of mirrored neighbours: two markers of one rigid segment exchanged where their
distances cannot tell.

Distances are blind to reflections. The toe and fifth-metatarsal markers of a foot are
nearly equidistant from its heel and ankle markers, so when they come back exchanged from
an occlusion every learned distance still fits and the exchange repair (``exchange``) has
nothing to go on. The handedness of the segment has: for four markers the signed volume

    V(a, b, c, d) = ((b - a) x (c - a)) . (d - a)

keeps its sign under every rigid motion and changes it when any two of them exchange. The
labeled first frame gives each segment's handedness.

At each template, each visible marker a with its three nearest visible neighbours b, c, d
that are rigid with it and with one another (every pair's learned distance variance at most
``RIGID_SD_MM``^2 plus the 2 sigma^2 noise adds to a distance) forms a quadruple. Its sine
s = V / (|b - a| |c - a| |d - a|) is compared with the first frame's: when the signs differ,
both are at least ``MIN_SINE`` (a near-flat quadruple has no handedness), and both lie
beyond ``SURE_SD`` sd of what noise and skin motion move them (sd(s) = sigma |grad s|,
first-order propagation of independent per-axis errors; sigma^2 the larger of the noise, at
most the least motion-residual variance of the markers over 6, and half the largest learned
distance variance in the quadruple), a is exchanged with its mirror in the quadruple: the
one of b, c, d whose learned distances to the other two agree with a's within
``TOLERANCE_MM``, so that every distance fits either way (none or two such, and nothing is
done: a flip that distances could have seen is the exchange repair's).

Measured (lp-l1): CMU 85_02 at 4 mm noise, seed 0, 98.13 -> 99.40 %; the rest of the seed-0
accuracy matrix within 0.3 point (96.26 -> 96.28 % mean over 85 rows) and the 80-row screen
of seeds 1-2 unchanged; the real wheelchair racing take 89.80 -> 91.60 %. Without the skin
motion in sigma, the real 135_02 fell 99.81 -> 98.17 %: its clavicle, C7 and acromia
quadruple flips through flat as the shoulders move, and the two were exchanged four times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.markers.exchange import reassigned
from formulations.markers.lengths import lengths
from formulations.markers.state import RIGID_SD_MM as RIGID_SD_MM
from formulations.markers.state import MarkerState

TOLERANCE_MM = 5.0  # a mirrored pair's learned distances to the rest agree within a few mm of skin motion
SURE_SD = 3.0  # a sign this many sd from 0 is the segment's, not the noise's
# A flatter quadruple flips through flat when one marker moves out of its plane by a few
# per cent of its size, which changes no distance to first order (shoulders shrugged about
# the clavicle-C7 line): 0.2 is a fifth of a right-angled corner's sine.
MIN_SINE = 0.2


def repair_mirrors(state: MarkerState, reference: np.ndarray) -> tuple[MarkerState, int]:
    """The state with mirrored pairs exchanged back (module doc), and how many pairs.

    Args:
        state: The markers at the template frame.
        reference: ``(N, 3)`` the labeled first frame (NaN where a marker had no position).
    """
    pairs, learned = 0, LearnedPairs.of(state)
    noise_var = _noise_var(state)
    quads, has = rigid_groups(state.visible, learned, rigid_bound(state), 4)
    has &= np.isfinite(reference[quads]).all(axis=(1, 2))
    s_now, s_then = sines(state.position[quads]), sines(reference[quads])
    # Most quadruples keep their sign: only the others are judged, one at a time.
    for a in np.flatnonzero(has & (s_now * s_then < 0)).tolist():
        quad = quads[a]
        spread = float(learned.var[np.ix_(quad, quad)][np.triu_indices(4, 1)].max())
        # Per-axis sd of each marker about the quadruple's rigid shape: the noise, or the skin
        # motion its distances show (a distance between markers moving by sigma each varies
        # by 2 sigma^2): near-flat quadruples of markers that slide a little flip without an
        # exchange (clavicle, C7 and the two acromia of CMU 135_02).
        if not _flipped(state.position[quad], reference[quad], float(np.sqrt(max(noise_var, spread / 2.0)))):
            continue
        partner = _mirror_partner(learned, quad)
        if partner is not None:
            state, pairs = _exchanged(state, a, partner), pairs + 1
    return state, pairs


@dataclass(frozen=True)
class LearnedPairs:
    """``(N, N)`` learned mean and variance of each pair's distance, from either marker's
    statistics (``MarkerState.distance_mean``/``distance_var``); inf where neither keeps it."""

    mean: np.ndarray
    var: np.ndarray

    @classmethod
    def of(cls, state: MarkerState) -> LearnedPairs:
        n, k = state.neighbours.shape
        rows, cols = np.repeat(np.arange(n), k), state.neighbours.ravel()
        mean, var = np.full((n, n), np.inf), np.full((n, n), np.inf)
        mean[rows, cols], var[rows, cols] = state.distance_mean.ravel(), state.distance_var.ravel()
        return cls(np.where(np.isfinite(mean), mean, mean.T), np.where(np.isfinite(var), var, var.T))


def _noise_var(state: MarkerState) -> float:
    """Per-axis noise variance, at most: 6 sigma^2 + q^2 of the calmest marker, q least."""
    return float(state.motion_var.min()) / 6.0


def rigid_bound(state: MarkerState) -> float:
    """Largest learned distance variance of two markers on one rigid segment: ``RIGID_SD_MM``
    squared plus the 2 sigma^2 that noise adds to a distance."""
    return RIGID_SD_MM**2 + 2.0 * _noise_var(state)


def rigid_groups(allowed: np.ndarray, learned: LearnedPairs, bound: float, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``(N, size)`` each marker and its ``size - 1`` nearest ``allowed`` markers rigid with it
    (learned distance variance at most ``bound``), and ``(N,)`` whether the marker is allowed
    with that many such, rigid with one another too.

    Fewer than ``size`` markers form no group: a take of one or two markers (or three, for
    quadruples) has nothing for the mirror and turn repairs to do.
    """
    n = len(allowed)
    if n < size:
        return np.zeros((n, size), dtype=int), np.zeros(n, dtype=bool)
    rigid = allowed[:, None] & allowed[None, :] & (learned.var <= bound) & ~np.eye(n, dtype=bool)
    near = np.where(rigid, learned.mean, np.inf)
    nearest = np.argsort(near, axis=1)[:, : size - 1]
    found = np.isfinite(np.take_along_axis(near, nearest, axis=1)).all(axis=1)
    inner = np.where(np.eye(size - 1, dtype=bool), 0.0, learned.var[nearest[:, :, None], nearest[:, None, :]])
    return np.column_stack([np.arange(n), nearest]), found & (inner.max(axis=(1, 2)) <= bound)


def sines(points: np.ndarray) -> np.ndarray:
    """``(Q,)`` V(a, b, c, d) over the product of the edges from a, for ``(Q, 4, 3)`` quadruples."""
    edges = points[:, 1:] - points[:, :1]
    volume = np.einsum("qi,qi->q", np.cross(edges[:, 0], edges[:, 1]), edges[:, 2])
    ratio: np.ndarray = volume / np.maximum(np.prod(lengths(edges), axis=1), 1e-12)
    return ratio


def _sine(points: np.ndarray) -> float:
    """The sine of one ``(4, 3)`` quadruple."""
    return float(sines(points[None])[0])


def _flipped(now: np.ndarray, then: np.ndarray, sigma: float) -> bool:
    """The quadruple's handedness differs from the first frame's, both beyond noise."""
    s_now, s_then = _sine(now), _sine(then)
    if s_now * s_then >= 0 or min(abs(s_now), abs(s_then)) < MIN_SINE:
        return False
    return min(abs(s_now) / _sine_sd(now, sigma), abs(s_then) / _sine_sd(then, sigma)) > SURE_SD


def _sine_sd(points: np.ndarray, sigma: float, step: float = 1e-3) -> float:
    """sigma |grad s|: the sine's sd under per-axis noise sigma (central differences)."""
    nudge = step * np.eye(12).reshape(12, 4, 3)
    grad = (sines(points[None] + nudge) - sines(points[None] - nudge)) / (2 * step)
    return max(sigma * float(np.linalg.norm(grad)), 1e-12)


def _mirror_partner(learned: LearnedPairs, quad: np.ndarray) -> int | None:
    """The one marker of the quadruple whose learned distances to the other two agree with
    a's within ``TOLERANCE_MM``: exchanged with a, every distance still fits."""
    a, others = int(quad[0]), quad[1:].tolist()
    mirrors = [
        x for x in others
        if all(abs(learned.mean[a, k] - learned.mean[x, k]) <= TOLERANCE_MM for k in others if k != x)
    ]
    return mirrors[0] if len(mirrors) == 1 else None


def _exchanged(state: MarkerState, a: int, b: int) -> MarkerState:
    visible = np.flatnonzero(state.visible)
    track = np.full(len(state.position), -1)
    track[visible] = np.arange(len(visible))
    track[a], track[b] = track[b], track[a]
    return reassigned(state, visible, state.position[visible], track)
