"""A constant-velocity Kalman filter on boxes, run for all objects at once.

State x = (cx, cy, w, h, vcx, vcy, vw, vh): box centre, width, height and their rates per
frame; measurement z = (cx, cy, w, h). One frame ahead

    x' = F x,   F = [[I, I], [0, I]],      P' = F P F^T + Q,
    Q = diag((s_p w, s_p h, s_p w, s_p h)^2, (s_v w, s_v h, s_v w, s_v h)^2),
    R = diag((s_m w, s_m h, s_m w, s_m h)^2),

with every deviation proportional to the box size, so that near and far people weigh the
same: BoT-SORT's model (Aharon et al. 2022; DeepSORT's with width in place of aspect),
s_p = s_m = 1/20 as there, but s_v = 1/40 where they take 1/160: people filmed by a walking
camera at 14 frames/s (MOT17-05) change speed in the image far more per frame than their
30 frames/s static views; 1/40 was chosen on TUD-Campus and MOT17-02 (``bench/mot_table.py``).
A new object starts from its first box with P = diag((2 s_p size)^2, (10 s_v size)^2), as there.

Hand-written rather than filterpy's ``KalmanFilter``: that filters one object at a time,
and the tracker advances some tens of objects every frame; here each step is one batch of
(N, 8, 8) products.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

POSITION_SD = 1.0 / 20.0
VELOCITY_SD = 1.0 / 40.0
MEASUREMENT_SD = 1.0 / 20.0

_F = np.block([[np.eye(4), np.eye(4)], [np.zeros((4, 4)), np.eye(4)]])


def measurement(corner: Array) -> Array:
    """``(..., 4)`` corners (x1, y1, x2, y2) -> ``(..., 4)`` z = (cx, cy, w, h)."""
    return np.concatenate([0.5 * (corner[..., :2] + corner[..., 2:]), corner[..., 2:] - corner[..., :2]], axis=-1)


def box_corners(z: Array) -> Array:
    """Inverse of ``measurement``."""
    return np.concatenate([z[..., :2] - 0.5 * z[..., 2:], z[..., :2] + 0.5 * z[..., 2:]], axis=-1)


def corner_rates(mean: Array) -> Array:
    """``(..., 4)`` rates of the corners per frame from states ``(..., 8)``."""
    result: Array = np.concatenate([mean[..., 4:6] - 0.5 * mean[..., 6:8], mean[..., 4:6] + 0.5 * mean[..., 6:8]], axis=-1)
    return result


def _size(mean: Array) -> Array:
    """``(N, 4)`` the (w, h, w, h) each deviation is proportional to."""
    wh = np.maximum(mean[:, 2:4], 1.0)
    result: Array = np.concatenate([wh, wh], axis=1)
    return result


def start(z: Array, velocity: Array | None = None) -> tuple[Array, Array]:
    """States and covariances ``(N, 8)``, ``(N, 8, 8)`` of new objects first seen as ``z`` ``(N, 4)``."""
    z = np.asarray(z, dtype=float).reshape(-1, 4)
    rate = np.zeros_like(z) if velocity is None else velocity
    mean = np.concatenate([z, rate], axis=1)
    size = _size(mean)
    deviation = np.concatenate([2.0 * POSITION_SD * size, 10.0 * VELOCITY_SD * size], axis=1)
    covariance = np.einsum("ni,ij->nij", deviation**2, np.eye(8))
    return mean, covariance


def predict(mean: Array, covariance: Array) -> tuple[Array, Array]:
    """One frame ahead for every object."""
    size = _size(mean)
    noise = np.concatenate([(POSITION_SD * size) ** 2, (VELOCITY_SD * size) ** 2], axis=1)
    moved = mean @ _F.T
    spread = _F @ covariance @ _F.T + np.einsum("ni,ij->nij", noise, np.eye(8))
    return moved, spread


def innovation(mean: Array, covariance: Array) -> tuple[Array, Array]:
    """Predicted measurement and its covariance S = H P H^T + R, ``(N, 4)``, ``(N, 4, 4)``."""
    r = (MEASUREMENT_SD * _size(mean)) ** 2
    return mean[:, :4].copy(), covariance[:, :4, :4] + np.einsum("ni,ij->nij", r, np.eye(4))


def update(mean: Array, covariance: Array, z: Array) -> tuple[Array, Array]:
    """Posterior of every object given its measurement ``z`` ``(N, 4)``."""
    predicted, s = innovation(mean, covariance)
    gain = np.linalg.solve(s, covariance[:, :4, :]).transpose(0, 2, 1)  # P H^T S^-1 (S symmetric)
    posterior = mean + np.einsum("nij,nj->ni", gain, z - predicted)
    spread = covariance - gain @ covariance[:, :4, :]
    return posterior, 0.5 * (spread + spread.transpose(0, 2, 1))


def mahalanobis(z: Array, predicted: Array, s: Array) -> Array:
    """Squared Mahalanobis distances ``(N, B)`` of ``B`` measurements to each of ``N`` predictions."""
    difference = z[None, :, :] - predicted[:, None, :]
    whitened = np.linalg.solve(np.linalg.cholesky(s)[:, None], difference[..., None])[..., 0]
    result: Array = (whitened**2).sum(axis=2)
    return result


_TO_CORNERS = np.array([[1.0, 0, -0.5, 0], [0, 1.0, 0, -0.5], [1.0, 0, 0.5, 0], [0, 1.0, 0, 0.5]])


def step_variance(size: Array, velocity_covariance: Array, frames: Array) -> Array:
    """``(C,)`` variance per corner coordinate of a step into a box of ``size`` (w, h) ``(C, 2)``.

    The step from box z_i to the next box z_j off the object's velocity v, e = z_j - z_i - v,
    carries two measurement noises, one frame's position noise, the velocity's own
    uncertainty P_vv (``velocity_covariance``, ``(C, 4, 4)``) and the velocity noise of the
    ``frames`` (``(C,)``) since the state, all but P_vv at the size of box j:

        C_j = 2 R + Q_p + P_vv + k Q_v   in (cx, cy, w, h),   s_j^2 = tr(T C_j T^T) / 4,

    T taking (cx, cy, w, h) to corners: one sd for all four corner coordinates, their mean variance.
    """
    wh = np.maximum(np.concatenate([size, size], axis=1), 1.0)
    position, velocity, measured = (POSITION_SD * wh) ** 2, (VELOCITY_SD * wh) ** 2, (MEASUREMENT_SD * wh) ** 2
    noise = 2.0 * measured + position + frames[:, None] * velocity
    diagonal = np.einsum("ai,ni,ai->n", _TO_CORNERS, noise, _TO_CORNERS)
    result: Array = (diagonal + np.einsum("ai,nij,aj->n", _TO_CORNERS, velocity_covariance, _TO_CORNERS)) / 4.0
    return result
