"""The take's own noise: measurement sigma and process noise from labeled positions.

Model, per axis: x_t = s_t + e_t, s the smooth true track, e white noise of variance
sigma^2. The residual of a motion model that extrapolates a polynomial of degree k - 1
through the k frames before t is the k-th difference

    D^k x_t = sum_i (-1)^i C(k, i) x_(t-i)        (k = 2: constant velocity,
                                                   k = 3: constant acceleration)

and on the noise Var(D^k e) = sigma^2 sum_i C(k, i)^2 = C(2k, k) sigma^2: 6 sigma^2 for
k = 2, 20 sigma^2 for k = 3. On the true track D^k s ~ s^(k) (one frame = 1), small when
the motion is smooth at the frame rate, large only at sudden changes (and at
mislabels), so a robust scale ignores it: with the median absolute residual (MAD about
0, the residual's mean),

    sigma = 1.4826 median |D^k x| / sqrt(C(2k, k))     (1.4826 = 1 / Phi^-1(3/4)).

Only frames where a marker was seen k + 1 frames in a row count (NaN elsewhere). The
process noise the costs would grow a prediction with is the true acceleration's scale:
Var(D^2 x) = Var(D^2 s) + 6 sigma^2, so q = sqrt(s_2^2 - 6 sigma^2), s_2 the robust scale of
D^2 x. Takes that were filtered before export have correlated noise, for which sigma
comes out below the raw sensor's.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb

import numpy as np

MAD_TO_SIGMA = 1.4826  # 1 / Phi^-1(3/4): the MAD of a Gaussian is 0.6745 sigma


@dataclass(frozen=True)
class TakeNoise:
    """What a take's labeled positions say about its noise, per axis (mm, frames).

    Attributes:
        measurement_mm: ``(3,)`` sigma of a position.
        acceleration_mm: ``(3,)`` q, the scale of the true acceleration (mm per frame^2).
    """

    measurement_mm: np.ndarray
    acceleration_mm: np.ndarray

    @classmethod
    def of(cls, positions: np.ndarray, order: int = 3) -> TakeNoise:
        """Estimate from ``(frames, markers, 3)`` labeled positions (NaN where unseen)."""
        sigma = measurement_noise(positions, order)
        second = robust_scale(np.diff(positions, n=2, axis=0))
        return cls(measurement_mm=sigma, acceleration_mm=np.sqrt(np.maximum(second**2 - 6 * sigma**2, 0.0)))

    def prediction_sigma_mm(self, unseen: np.ndarray) -> np.ndarray:
        """``(..., 3)`` sigma of a candidate's offset from a constant-velocity prediction.

        ``unseen`` frames without the marker (0: seen in the frame before), so the
        prediction reaches h = unseen + 1 frames past the last sighting x_0. Then
        x^ = x_0 + h (x_0 - x_-1) errs by e_0 (1 + h) - h e_-1 from noise and by
        sum_j (h - j + 1) a_j from the accelerations a_j (j = 1..h, white, scale q), and
        the candidate adds its own e:

            var = sigma^2 ((1 + h)^2 + h^2 + 1) + q^2 h (h + 1) (2h + 1) / 6,

        which at h = 1 is Var(D^2 x) = 6 sigma^2 + q^2, the constant-velocity residual.
        """
        h = np.asarray(unseen, dtype=float)[..., None] + 1
        noise = self.measurement_mm**2 * ((1 + h) ** 2 + h**2 + 1)
        process = self.acceleration_mm**2 * h * (h + 1) * (2 * h + 1) / 6
        sigma: np.ndarray = np.sqrt(noise + process)
        return sigma


def measurement_noise(positions: np.ndarray, order: int = 3) -> np.ndarray:
    """``(3,)`` sigma per axis (mm) from the order-``order`` motion-model residual (module doc).

    Args:
        positions: ``(frames, markers, 3)`` labeled positions, NaN where a marker is unseen.
        order: k, 2 (constant velocity) or more; 3 (constant acceleration) by default, as
            at 120 Hz a limb's acceleration changes little from frame to frame but its
            velocity does.
    """
    sigma: np.ndarray = robust_scale(np.diff(positions, n=order, axis=0)) / np.sqrt(comb(2 * order, order))
    return sigma


def robust_scale(residual: np.ndarray) -> np.ndarray:
    """``(3,)`` 1.4826 median |r| per axis over every finite residual of ``(..., 3)``."""
    flat = residual.reshape(-1, 3)
    scale: np.ndarray = MAD_TO_SIGMA * np.nanmedian(np.abs(flat), axis=0)
    return scale
