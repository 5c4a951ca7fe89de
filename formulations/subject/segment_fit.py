"""One rigid segment over time: its marker constellation and its pose in every frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rigid import rigid_transform

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SegmentFit:
    """A segment's constellation and poses: marker p at frame k is z_p(k) ~ R(k) u_p + d(k).

    Attributes:
        markers: Marker indices (columns of the take).
        coordinates: ``(P, 3)`` u_p in the segment frame (origin at the centroid, principal axes).
        rotation: ``(K, 3, 3)`` R(k); NaN in frames with fewer than 3 of its markers.
        origin: ``(K, 3)`` d(k), the segment frame's origin in the world; NaN likewise.
        spread: ``(P,)`` RMS distance of each marker from its rigid prediction, mm.
    """

    markers: list[int]
    coordinates: Array
    rotation: Array
    origin: Array
    spread: Array

    @property
    def valid(self) -> NDArray[np.bool_]:
        return np.asarray(np.isfinite(self.origin).all(axis=1), dtype=bool)


def fit_segment(positions: Array, markers: list[int], rounds: int = 3) -> SegmentFit:
    """Generalised Procrustes: the mean shape u and per-frame Kabsch poses (R(k), d(k)).

    Starting from the frame that sees most of the markers, each round aligns every frame to
    the shape by the weighted Kabsch of ``rigid_transform`` (weight 0 for a missing marker),
    so R(k) minimises sum_p w_p(k) |R(k)(u_p - c_s) + c_t - z_p(k)|^2, then sets
    u_p = mean_k R(k)^T (z_p(k) - d(k)) with d(k) = c_t - R(k) c_s.
    """
    z = positions[:, markers]
    seen: NDArray[np.bool_] = np.asarray(np.isfinite(z).all(axis=2), dtype=bool)
    usable = seen.sum(axis=1) >= 3
    if not usable.any():
        raise ValueError("no frame sees 3 markers of the segment")
    first = int(np.argmax(seen.sum(axis=1)))
    shape = np.where(seen[first, :, None], z[first], np.nanmean(z[usable], axis=0))
    shape = shape - shape.mean(axis=0)
    weight = seen[usable].astype(float)
    target = np.where(seen[usable, :, None], z[usable], 0.0)
    for _ in range(rounds):
        source = np.broadcast_to(shape, target.shape)
        rot, c_s, c_t = rigid_transform(source, target, weight)
        origin = c_t - np.einsum("kij,kj->ki", rot, c_s)
        local = np.einsum("kji,kpj->kpi", rot, target - origin[:, None])
        local = np.where(seen[usable, :, None], local, np.nan)
        shape = np.nanmean(local, axis=0)
        shape = shape - shape.mean(axis=0)
    _, _, axes = np.linalg.svd(shape, full_matrices=False)
    axes = axes * np.sign(np.linalg.det(axes))  # a proper rotation: the frame keeps its handedness
    shape = shape @ axes.T
    source = np.broadcast_to(shape, target.shape)
    rot, c_s, c_t = rigid_transform(source, target, weight)
    rotation = np.full((len(z), 3, 3), np.nan)
    origin = np.full((len(z), 3), np.nan)
    rotation[usable] = rot
    origin[usable] = c_t - np.einsum("kij,kj->ki", rot, c_s)
    residual = np.einsum("kij,pj->kpi", rotation, shape) + origin[:, None] - z
    spread = np.sqrt(np.nanmean(np.einsum("kpi,kpi->kp", residual, residual), axis=0))
    return SegmentFit(list(markers), shape, rotation, origin, spread)
