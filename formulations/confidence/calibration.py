"""The reported confidence: the window's probability calibrated against how often labels are right.

``probability`` reads the window cost as a negative log-likelihood, but the costs are
hand-set (mm, not nats), and ``carried`` and the shape checks lower a label's p on evidence
that often turns out harmless. Measured against the truth over the accuracy matrix's
tuning half (seed 0, five conditions, 40 takes x conditions, 621,574 labels, lp-l1), the
raw p is far too low where it is low: labels at p < 0.01 were right 61 % of the time, at
0.8-0.9 98.1 %. So a reported "90 % sure" did not mean 90 %.

The raw p is kept for labeling itself (the exchange repair, the forgetting of doubtful
shapes and the second pass's trigger were all chosen on it, at 0.9). A result reports
each label's p through a monotone map, fitted once by isotonic regression
(``fit_calibration``, the pool-adjacent-violators algorithm of
``scipy.optimize.isotonic_regression``) of right (1) / wrong (0) on the raw p, in bins of
its logit, and interpolated linearly between the bins' mean raw p. The map is strictly
increasing around 0.9, so the labels reported below its value there are exactly those
the labeler counted doubtful: the flag, the doubtful share and the window statistics do
not move, only what the numbers mean. ``bench/confidence_calibration.py`` refits it and
prints its reliability on the validation half.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import isotonic_regression

LOGIT_EDGES = np.arange(-9.0, 10.0, 1.0)  # bin edges of logit(p): p from 1e-4 to 1 - 1e-4, one nat apart
MIN_BIN_LABELS = 200  # a bin with fewer labels is merged into the next: its rate would be noise


@dataclass(frozen=True)
class ConfidenceCalibration:
    """A monotone map from raw label probabilities to calibrated ones.

    Attributes:
        raw: Increasing knots in [0, 1]: the mean raw p of each fitted bin.
        right: Non-decreasing share of right labels at each knot.
    """

    raw: tuple[float, ...]
    right: tuple[float, ...]

    def __call__(self, probability: ArrayLike) -> np.ndarray:
        """The calibrated probabilities (NaN stays NaN; below or above the knots, the end values)."""
        p = np.asarray(probability, dtype=float)
        calibrated: np.ndarray = np.where(np.isnan(p), np.nan, np.interp(np.nan_to_num(p), self.raw, self.right))
        return calibrated


def fit_calibration(raw: np.ndarray, right: np.ndarray) -> ConfidenceCalibration:
    """The isotonic calibration of labels' raw probabilities ``raw`` against ``right``
    (both ``(L,)``; module doc)."""
    raw = np.asarray(raw, dtype=float)
    right = np.asarray(right, dtype=float)
    logit = np.log(np.clip(raw, 1e-12, 1.0)) - np.log(np.clip(1.0 - raw, 1e-12, 1.0))
    bins = np.digitize(logit, LOGIT_EDGES)
    means, rates, counts = [], [], []
    pending = np.zeros(len(raw), bool)
    for b in range(len(LOGIT_EDGES) + 1):
        pending |= bins == b
        if pending.sum() >= MIN_BIN_LABELS or (b == len(LOGIT_EDGES) and pending.any()):
            means.append(raw[pending].mean())
            rates.append(right[pending].mean())
            counts.append(pending.sum())
            pending[:] = False
    fitted = isotonic_regression(np.array(rates), weights=np.array(counts, dtype=float), increasing=True).x
    return ConfidenceCalibration(tuple(float(m) for m in means), tuple(float(r) for r in fitted))


# Fitted by ``python bench/confidence_calibration.py`` on the accuracy matrix's tuning half
# (seed 0, 600 frames, five conditions, lp-l1: 621,574 labels, 3.58 % wrong); flat runs merged.
LABEL_CALIBRATION = ConfidenceCalibration(
    raw=(4.6184e-06, 0.00020464, 0.029196, 0.08468, 0.19197, 0.38111, 0.61391, 0.80971, 0.9251, 0.96892, 0.98812,
         0.99946, 0.99979, 0.99997),
    right=(0.59309, 0.6266, 0.6266, 0.71042, 0.71042, 0.83228, 0.85472, 0.96761, 0.99175, 0.99522, 0.99831, 0.99831,
           0.99886, 0.9999),
)
