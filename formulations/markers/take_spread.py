"""How much each marker-neighbour distance varies over a whole labeled take.

The labeler learns the spread of each distance online (``MarkerState.distance_var``), from a
prior of 100 mm^2 at the rate of 0.03 a frame. Early in a take that prior is all it has:
a forearm marker and a trunk marker are judged as if 10 mm apart at most, so at a serve's
first swing the shape term holds arm markers to where the trunk says they belong and the
arm's markers exchange. Ringer & Lasenby (2004, Sec. 3) compute the same spreads, their
matrix D, over the whole sequence. A first labeling of the take gives them: its labels are
mostly right, and a spread only needs the distance over the frames where both markers were
labeled.

Per marker m and neighbour j, over the frames where both were labeled,

    var_mj = ((P90(d_mj) - P10(d_mj)) / 2.563)^2,   floored at ``SPREAD_FLOOR_MM2``,

the variance of a normal distribution with those deciles: a first pass that gave m a wrong
point in up to a tenth of those frames leaves it unchanged, where the plain variance of
``subject.distances.distance_spread`` (the model fit's D, over every pair) would call the
pair loose. Pairs labeled together in fewer than ``MIN_FRAMES`` frames keep the state's prior.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.markers.lengths import lengths
from formulations.markers.state import MarkerState

Array = NDArray[np.float64]

DECILE_SPAN_SD = 2.563  # P90 - P10 of a normal distribution, in standard deviations
SPREAD_FLOOR_MM2 = 1.0  # below the noise of a distance between two centroids
MIN_FRAMES = 20  # fewer frames labeled together say too little of a spread
# One labeling is read here several times (03_rolling: 16 calls on 11 labelings, the take-wide
# exchanges and hand-overs, the second pass, the pass judges): the last few spreads are kept
# by the labeling's content (sha256, 1.7 ms against 25 ms a spread at 1,743 frames of 62 markers).
RECENT_SPREADS = 4
_recent: OrderedDict[bytes, Array] = OrderedDict()
_recent_lock = threading.Lock()


def take_spread(positions: Array, neighbours: NDArray[np.int64]) -> Array:
    """``(N, K)`` variance of each marker-neighbour distance (module doc), NaN where the pair
    was labeled together in fewer than ``MIN_FRAMES`` frames.

    Args:
        positions: ``(F, N, 3)`` labeled positions, NaN where a marker has no label.
        neighbours: ``(N, K)`` each marker's neighbours.
    """
    key = hashlib.sha256()
    for part in (np.asarray(positions, float), np.asarray(neighbours, np.int64)):
        key.update(repr(part.shape).encode())
        key.update(part.tobytes())
    digest = key.digest()
    with _recent_lock:
        known = _recent.get(digest)
        if known is not None:
            _recent.move_to_end(digest)
            return known.copy()
    spread = _spread(positions, neighbours)
    with _recent_lock:
        _recent[digest] = spread.copy()
        while len(_recent) > RECENT_SPREADS:
            _recent.popitem(last=False)
    return spread


def _spread(positions: Array, neighbours: NDArray[np.int64]) -> Array:
    """``take_spread`` computed."""
    spread = np.full(neighbours.shape, np.nan)
    track = np.ascontiguousarray(positions.transpose(1, 0, 2))  # (N, F, 3): a neighbour's frames in one block
    # marker by marker: (K, F) at a time, where (F, N, K, 3) at once took 200 MB for 5,200
    # frames of 41 markers, and gigabytes for a long take assembled by the service
    for m in range(len(neighbours)):
        spread[m] = decile_spread(lengths(track[m] - track[neighbours[m]]))  # (K, F) distances
    return spread


def decile_spread(values: Array) -> Array:
    """``(K,)`` the spread of each row of ``values`` ``(K, F)`` as the module doc takes a
    distance's: ((P90 - P10) / ``DECILE_SPAN_SD``)^2 over its finite values, floored at
    ``SPREAD_FLOOR_MM2``; NaN for a row with fewer than ``MIN_FRAMES``."""
    spread = np.full(len(values), np.nan)
    enough = np.isfinite(values).sum(axis=1) >= MIN_FRAMES
    if enough.any():
        low, high = _deciles(values[enough])
        spread[enough] = np.maximum(((high - low) / DECILE_SPAN_SD) ** 2, SPREAD_FLOOR_MM2)
    return spread


def _deciles(distance: Array) -> Array:
    """``(2, K)`` P10 and P90 of each row of ``distance`` ``(K, F)`` over its n >= 2 finite values.

    numpy's default (linear) percentile of the sorted values s, for all rows at once where
    ``np.nanpercentile`` takes them one by one in Python (most of this module's time): with
    j = floor((n - 1) q) and g = (n - 1) q - j, P_q = s_j + g (s_{j+1} - s_j), computed from
    the nearer of s_j and s_{j+1} as numpy does, so every value is ``np.nanpercentile``'s.
    """
    ordered = np.sort(distance, axis=1)  # NaN last
    at = np.array([[0.1], [0.9]]) * (np.isfinite(distance).sum(axis=1) - 1)  # (2, K): (n - 1) q
    j = np.floor(at).astype(np.int64)
    g = at - j
    low, high = np.take_along_axis(ordered, j.T, axis=1).T, np.take_along_axis(ordered, j.T + 1, axis=1).T
    step = high - low
    decile: Array = np.where(g >= 0.5, high - step * (1 - g), low + step * g)
    return decile


def with_take_spread(state: MarkerState, positions: Array) -> MarkerState:
    """``state`` with each distance variance the take's spread where it is known."""
    spread = take_spread(positions, state.neighbours)
    return replace(state, distance_var=np.where(np.isfinite(spread), spread, state.distance_var))
