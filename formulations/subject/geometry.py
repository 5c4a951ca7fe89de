"""A subject model as arrays, with the tolerances identification and prediction use.

Every tolerance comes from the model itself: a marker p of a segment is expected within

    tau_p = sigmas * s_p + r

of where its segment's pose puts it, s_p its spread (the RMS distance from its rigid
prediction over the takes the model was fitted on: noise and skin motion) and r the marker
radius (two distinct markers cannot be closer than 2 r, so a point within r of a prediction
is that marker's or nobody's). A joint centre seen from its two segments agrees within
sigmas * rms_joint + 2 r, and a single marker's distance to a segment origin within
sigmas * sd + r.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.subject.model import SubjectModel

Array = NDArray[np.float64]
Index = NDArray[np.int64]


@dataclass(frozen=True)
class SegmentGeometry:
    """One segment: its markers (indices into ``ModelGeometry.names``), coordinates ``(S, 3)``,
    spreads and tolerances ``(S,)``."""

    name: str
    markers: Index
    coordinates: Array
    spread: Array
    tolerance: Array


@dataclass(frozen=True)
class JointGeometry:
    """A joint between segments ``a`` and ``b`` (indices), its centre in each frame, the agreement
    tolerance, the rms with which the fit's two segments agree on the centre (mm), and b's rest
    rotation in a's frame (``joint_rest``; None if the model has none)."""

    a: int
    b: int
    centre_a: Array
    centre_b: Array
    tolerance: float
    rms: float
    rest: Array | None = None


@dataclass(frozen=True)
class SingleGeometry:
    """A marker on no segment: its index, the segments it is measured from, mean distances and tolerances."""

    marker: int
    segments: Index
    distances: Array
    tolerance: Array


@dataclass(frozen=True)
class ModelGeometry:
    """The model's markers (segments' in order, then singles), segments, joints and singles."""

    names: list[str]
    segments: list[SegmentGeometry]
    joints: list[JointGeometry]
    singles: list[SingleGeometry]
    segment_of: Index  # (N,) segment of each marker, -1 for a single
    radius: float
    sigmas: float

    @classmethod
    def of(cls, model: SubjectModel, sigmas: float = 3.0) -> ModelGeometry:
        names = [m for s in model.segments for m in s.markers] + [s.marker for s in model.singles]
        if len(set(names)) != len(names):
            twice = next(name for name in names if names.count(name) > 1)
            raise ValueError(f"marker {twice!r} is on two segments of the model (or a segment and a single)")
        index = {name: i for i, name in enumerate(names)}
        seg_index = {s.name: i for i, s in enumerate(model.segments)}
        r = model.marker_radius
        segments = [
            SegmentGeometry(
                s.name, np.array([index[m] for m in s.markers], dtype=np.int64), np.asarray(s.coordinates, dtype=float),
                np.asarray(s.spread, dtype=float), sigmas * np.asarray(s.spread, dtype=float) + r,
            )
            for s in model.segments
        ]
        joints = [
            JointGeometry(
                seg_index[j.segments[0]], seg_index[j.segments[1]], np.asarray(j.centres[0], dtype=float),
                np.asarray(j.centres[1], dtype=float), sigmas * j.rms + 2 * r, j.rms,
                None if j.rest is None else np.asarray(j.rest, dtype=float),
            )
            for j in model.joints
        ]
        singles = [
            SingleGeometry(
                index[s.marker], np.array([seg_index[n] for n in s.segments], dtype=np.int64),
                np.asarray(s.distances, dtype=float), sigmas * np.asarray(s.sd, dtype=float) + r,
            )
            for s in model.singles
        ]
        segment_of = np.full(len(names), -1, dtype=np.int64)
        for k, segment in enumerate(segments):
            segment_of[segment.markers] = k
        return cls(names, segments, joints, singles, segment_of, r, sigmas)

    def in_model_order(self, names: list[str], positions: Array) -> Array:
        """``(F, N_model, 3)`` the columns of ``positions`` ``(F, len(names), 3)`` in the model's
        marker order; NaN for model markers ``names`` does not have."""
        column = {name: i for i, name in enumerate(names)}
        ordered = np.full((len(positions), len(self.names), 3), np.nan)
        for k, name in enumerate(self.names):
            if name in column:
                ordered[:, k] = positions[:, column[name]]
        return ordered

    @property
    def tolerance(self) -> Array:
        """``(N,)`` tau of every marker (a single's: its tightest distance tolerance)."""
        tau = np.full(len(self.names), np.nan)
        for segment in self.segments:
            tau[segment.markers] = segment.tolerance
        for single in self.singles:
            tau[single.marker] = single.tolerance.min()
        return tau
