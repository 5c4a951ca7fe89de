"""Where each marker is, from the detections the cameras' own tracking assigned to it.

``per-camera`` association tracks every marker in every camera separately, so a marker
may carry a wrong detection in one camera. The cameras are checked against each other
(Ringer & Lasenby 2004, Sec. 2, step 3, with a consensus test in front). For marker n
with views V_n (the cameras that assigned it a detection u_nc) and prediction p_n:

1. Every subset S of V_n with |S| >= 2 is triangulated (DLT, ``Rig.triangulate``) and is
   consistent when its largest view error max_{c in S} ||project_c(X_S) - u_nc|| <= tau.
   The largest error rather than the RMS is tested: one wrong view of four is diluted in
   the RMS. X_n is the point of the largest consistent subset; among subsets of that size,
   the one nearest p_n. Dropping the worst view greedily instead fails when a wrong view
   drags the point enough that a right view reprojects worse than it (seen on CMU 85_02:
   of three views, the right one dropped and the wrong pair kept). With C cameras there
   are 2^C - C - 1 subsets, all triangulated in one batch: cheap for the 4 to 8 cameras
   of a lab rig. Most markers have no wrong view: all of V_n is triangulated first, and
   only the markers whose full set fails go through the subsets (the full set, when
   consistent, is the only subset of the largest size, so the answer is the same).
2. No consistent subset (the rays do not meet) but views: only the prediction can say
   which is right; keep the view whose detection lies nearest project_c(p_n), go to 3.
3. One view: X_n = ``ray_compromise`` (the point of the ray nearest p_n).
4. No view: X_n = p_n, flagged as filled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.cameras.rig import Rig


@dataclass(frozen=True)
class FrameViews:
    """One frame's detections, in pixels and undistorted, per camera.

    Attributes:
        pixels: ``pixels[c]`` ``(D_c, 2)`` detections of camera c.
        normalised: ``normalised[c]`` the same, undistorted (``Camera.undistort``).
    """

    pixels: list[np.ndarray]
    normalised: list[np.ndarray]

    def of(self, views: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(N, C, 2)`` pixels and normalised coordinates of the detection each marker took, NaN where -1.

        Args:
            views: ``(N, C)`` detection index per marker and camera, -1 for none.
        """
        pixels, normalised = np.full(views.shape + (2,), np.nan), np.full(views.shape + (2,), np.nan)
        for c, (found, flat) in enumerate(zip(self.pixels, self.normalised)):
            took = views[:, c] >= 0
            pixels[took, c], normalised[took, c] = found[views[took, c]], flat[views[took, c]]
        return pixels, normalised


@dataclass(frozen=True)
class LocatedMarkers:
    """Markers of one frame located from their views.

    Attributes:
        point: ``(N, 3)`` position: triangulated, on the one ray, or the prediction.
        kept: ``(N, C)`` True for the views that survived the consistency test.
    """

    point: np.ndarray
    kept: np.ndarray

    @property
    def n_views(self) -> np.ndarray:
        """``(N,)`` views behind each position (0: the position is the prediction)."""
        n_views: np.ndarray = self.kept.sum(axis=1)
        return n_views


def locate_markers(
    rig: Rig, pixels: np.ndarray, normalised: np.ndarray, prediction: np.ndarray, max_error_px: float = 2.0
) -> LocatedMarkers:
    """Triangulate each marker from its largest consistent set of views (module doc).

    Args:
        rig: The C cameras.
        pixels: ``(N, C, 2)`` detection each marker took in each camera, NaN where none.
        normalised: The same detections undistorted (``FrameViews.of``, ``Rig.undistort``).
        prediction: ``(N, 3)`` predicted positions.
        max_error_px: tau, the largest reprojection error a kept view may have.
    """
    prediction = np.asarray(prediction, dtype=float)
    has = np.isfinite(pixels).all(axis=2)
    point, kept = prediction.copy(), np.zeros_like(has)
    full = np.flatnonzero(has.sum(axis=1) >= 2)
    points = rig.triangulate(normalised[full])
    agree = np.nanmax(rig.errors(points, pixels[full]), axis=1) <= max_error_px
    point[full[agree]], kept[full[agree]] = points[agree], has[full[agree]]
    _best_subsets(rig, pixels, normalised, prediction, full[~agree], max_error_px, point, kept)

    single = np.flatnonzero(has.any(axis=1) & ~kept.any(axis=1))
    off_prediction = np.linalg.norm(rig.project(prediction[single]) - pixels[single], axis=2)
    kept[single, np.nanargmin(off_prediction, axis=1)] = True
    for c in range(len(rig)):
        alone = np.flatnonzero(kept[:, c] & (kept.sum(axis=1) == 1))
        if len(alone):
            point[alone] = rig.on_ray(c, normalised[alone, c], prediction[alone])
    return LocatedMarkers(point=point, kept=kept)


def _best_subsets(
    rig: Rig, pixels: np.ndarray, normalised: np.ndarray, prediction: np.ndarray, markers: np.ndarray,
    max_error_px: float, point: np.ndarray, kept: np.ndarray,
) -> None:
    """Fill ``point`` and ``kept`` for ``markers`` (full set inconsistent) from their best proper subset."""
    has = np.isfinite(pixels[markers]).all(axis=2)
    subsets = _view_subsets(len(rig))
    proper = (subsets[None] <= has[:, None]).all(axis=2) & (subsets[None] != has[:, None]).any(axis=2)
    row, subset = np.nonzero(proper)
    if len(row) == 0:
        return
    marker, mask = markers[row], subsets[subset][..., None]
    points = rig.triangulate(np.where(mask, normalised[marker], np.nan))
    consistent = np.nanmax(rig.errors(points, np.where(mask, pixels[marker], np.nan)), axis=1) <= max_error_px
    marker, subset, points = marker[consistent], subset[consistent], points[consistent]
    order = np.lexsort((np.linalg.norm(points - prediction[marker], axis=1), -subsets[subset].sum(axis=1), marker))
    best = order[np.unique(marker[order], return_index=True)[1]]
    point[marker[best]], kept[marker[best]] = points[best], subsets[subset[best]]


def _view_subsets(n_cameras: int) -> np.ndarray:
    """``(S, C)`` bool, every subset of two or more cameras."""
    every = (np.arange(2**n_cameras)[:, None] >> np.arange(n_cameras)) & 1
    subsets: np.ndarray = every[every.sum(axis=1) >= 2].astype(bool)
    return subsets
