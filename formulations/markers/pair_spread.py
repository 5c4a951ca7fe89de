"""How much each marker-pair distance varies over a labeled take, robust to many wrong labels,
each pair computed once.

The take-wide rotation and half-turn judges (``take_rotation``, ``take_flip``) weigh every
marker of a candidate set against its witnesses. Candidate sets share most of their pairs
(03_rolling: 164 triangles and 15 plates over 68 markers), and the spread of one pair is a
median over the whole take, so computing it once per pair, not once per set, is what keeps
the judges cheap. Per pair (a, b) over the frames labeling both,

    var_ab = (MAD_TO_SIGMA * median_t |d_ab(t) - median_t d_ab|)^2,   floored at ``SPREAD_FLOOR_MM2``,

the squared median absolute deviation: near right while well under half of those frames are
wrong (a rotation over 40 % of a take; ``take_spread``'s deciles hold to a tenth, and the
first frame's distance is one pose: CMU 135_02's ankle to fifth metatarsal 109 mm there, 103
over the take); inf where fewer than ``MIN_FRAMES`` frames label both, or a = b.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.noise import MAD_TO_SIGMA
from formulations.markers.rigid import RIGID_SD_MM
from formulations.markers.take_spread import MIN_FRAMES, SPREAD_FLOOR_MM2

Array = NDArray[np.float64]


class PairSpreads:
    """The robust spread (module doc) of the pairs asked for, over ``positions`` ``(F, N, 3)``
    as they were given: a labeling changed since needs a new one."""

    def __init__(self, positions: Array) -> None:
        self._positions = positions
        self._var = np.full((positions.shape[1],) * 2, np.nan)  # NaN: not computed yet
        self._median = np.full((positions.shape[1],) * 2, np.nan)

    def var(self, rows: list[int], columns: list[int]) -> Array:
        """``(R, C)`` the spread of each pair (mm^2)."""
        block = np.ix_(rows, columns)
        todo = np.nonzero(np.isnan(self._var[block]))
        if todo[0].size:
            a, b = np.asarray(rows)[todo[0]], np.asarray(columns)[todo[1]]
            median, var = _robust_stats(self._positions, a, b)
            self._var[a, b] = self._var[b, a] = var
            self._median[a, b] = self._median[b, a] = median
        spread: Array = self._var[block]
        return spread

    def median(self, rows: list[int], columns: list[int]) -> Array:
        """``(R, C)`` the median distance of each pair over the frames labeling both (mm); NaN
        where its spread is inf (too few frames, or a = b)."""
        self.var(rows, columns)
        median: Array = self._median[np.ix_(rows, columns)]
        return median

    def rigid(self, rows: list[int], columns: list[int]) -> NDArray[np.bool_]:
        """``(R, C)`` pairs whose spread is a rigid one's (``RIGID_SD_MM``); False for a = b."""
        rigid: NDArray[np.bool_] = np.asarray(self.var(rows, columns) <= RIGID_SD_MM**2)
        return rigid


def _robust_stats(positions: Array, a: NDArray[np.intp], b: NDArray[np.intp]) -> tuple[Array, Array]:
    """``(P,)`` the median distance and the spread of each pair (a[p], b[p]) (module doc)."""
    d = np.linalg.norm(positions[:, a] - positions[:, b], axis=2)  # (F, P)
    enough = np.isfinite(d).sum(axis=0) >= MIN_FRAMES
    with np.errstate(all="ignore"):
        d = np.where(enough, d, 0.0)
        median = np.nanmedian(d, axis=0)
        off = np.nanmedian(np.abs(d - median), axis=0)
    var: Array = np.maximum((MAD_TO_SIGMA * off) ** 2, SPREAD_FLOOR_MM2)
    unknown = ~enough | (a == b)
    var[unknown], median[unknown] = np.inf, np.nan
    return median, var
