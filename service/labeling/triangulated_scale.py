"""Do the triangulated markers keep the labeled first frame's size? A focal length off on every camera.

In camera mode the labels' 3D positions are triangulated through the calibration. A focal
length off by the same factor on every camera passes every other check: the cameras still
agree with each other (no camera's detections go unused), and frame 0's projections land
3-7.5 px off at 5 %, under the frame-0 check's 10 px. The triangulated body is then scaled
about the rig: through the Pose2Sim rig, CMU 85_02's labels sat 22-24 mm (median) off the
truth at 5 % and 9 mm at 2 %, and nothing was said.

The labeled first frame keeps the true size, so the scale shows in pairs of markers that
keep their distance: for each marker n and its ``NEIGHBOURS`` nearest markers m in the first
frame,

    r_nm(t) = |x_n(t) - x_m(t)| / |x_n(0) - x_m(0)|      (t >= 1, both labeled),

a pair is rigid when its ratios stay within ``RIGID_SPREAD`` of their median (MAD-scaled, over
``MIN_FRAMES`` frames or more), and the median over the rigid pairs of their median ratio is
the triangulation's scale. A limb that bends or a label that jumps to another marker makes its
pairs loose, so they do not vote: with every near pair voting, the wheelchair racing take's
3-marker clusters (30 mm apart, merged into one blob at 3 px) read 2-6 % "further apart"
through a right calibration.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.noise import MAD_TO_SIGMA

NEIGHBOURS = 6  # each marker's nearest in the first frame: on its own segment, mostly
RIGID_SPREAD = 0.02  # MAD-scaled sd of a pair's ratio: 2 mm in 100 mm
MIN_FRAMES = 10  # labeled together in fewer, a pair's spread says little
MIN_PAIRS = 10  # fewer rigid pairs say little
SCALE_TOLERANCE = 0.015  # |scale - 1| above it: a 2 % focal error gives 1.9 %


def triangulated_scale(positions: np.ndarray) -> tuple[float, int]:
    """The scale (module doc) of ``positions`` ``(F, N, 3)`` (frame 0 the labeled one, NaN where
    unlabeled), and how many rigid pairs it is the median of (NaN and 0 with none)."""
    first = positions[0]
    known = np.flatnonzero(np.isfinite(first).all(axis=1))
    if len(positions) < 2 or len(known) < 2:
        return float("nan"), 0
    spacing = np.linalg.norm(first[known, None] - first[None, known], axis=2)
    np.fill_diagonal(spacing, np.inf)
    nearest = np.argsort(spacing, axis=1)[:, : min(NEIGHBOURS, len(known) - 1)]
    pairs = np.unique(np.sort(np.column_stack([np.repeat(np.arange(len(known)), nearest.shape[1]), nearest.ravel()]),
                              axis=1), axis=0)
    base = spacing[pairs[:, 0], pairs[:, 1]]
    a, b = known[pairs[:, 0]], known[pairs[:, 1]]
    ratio = np.linalg.norm(positions[1:, a] - positions[1:, b], axis=2) / np.where(base > 0, base, np.nan)  # (F-1, P)
    ratio = ratio[:, np.isfinite(ratio).sum(axis=0) >= MIN_FRAMES]
    if not ratio.shape[1]:
        return float("nan"), 0
    median = np.nanmedian(ratio, axis=0)
    spread = MAD_TO_SIGMA * np.nanmedian(np.abs(ratio - median), axis=0)
    rigid = median[spread <= RIGID_SPREAD * median]
    return (float(np.median(rigid)), len(rigid)) if len(rigid) else (float("nan"), 0)


def triangulated_scale_warning(positions: np.ndarray) -> str | None:
    """A line when the scale (module doc) is off 1 by more than ``SCALE_TOLERANCE``, None otherwise."""
    scale, pairs = triangulated_scale(positions)
    if pairs < MIN_PAIRS or not abs(scale - 1.0) > SCALE_TOLERANCE:
        return None
    how = f"{1 - scale:.1%} closer together" if scale < 1 else f"{scale - 1:.1%} further apart"
    return (f"warning: the triangulated markers sit {how} than in the labeled first frame (median over {pairs} pairs "
            "that keep their distance): is every camera's focal length right (5 % off does this to about 5 %), and "
            "the first frame from this calibration?")
