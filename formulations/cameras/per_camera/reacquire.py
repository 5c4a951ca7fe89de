"""A second view for markers that only one camera kept: search the epipolar band.

A marker that no two cameras agree on for long is carried by a prediction that drifts
(the rigid motion of its neighbours, then damped velocity), and once the prediction is far
off, the per-camera gates can no longer tell its detections from the others: the marker
stays on one camera's ray, and its position along that ray is the drifting prediction.
The one view it keeps is still good evidence, and so is the body: the marker keeps its
distances to the neighbours on its segment. For marker n with its single view u_na in
camera a, every detection u_d of another camera b that no marker located by two or more
cameras kept this frame is tried:
the pair is triangulated (``Rig.triangulate``) and accepted when

    max(||project_a(X) - u_na||, ||project_b(X) - u_d||) <= tau,  X in front of both,
    s_n(X) = sum_j a_j | ||X - X_j|| - dbar_nj | / sum_j a_j <= s_max,

i.e. u_d lies in the epipolar band of u_na and X sits where the marker's neighbours j say
it should: X_j their positions this frame (those located by two or more cameras),
dbar_nj the learned mean distances and a_j = 1 / (var_nj + 1) (``MarkerState``), the shape
signature of ``cloud_candidates``. The prediction is not asked: it is what drifted. Of
the accepted pairs the one with the smallest s_n wins; markers competing for one
detection are served best first. Detections no well-located marker holds are clutter, or
belong to lost markers, so a wrong pick needs one of them in the band at the right
distances.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from formulations.cameras.per_camera.gating import PerCameraGating
from formulations.cameras.per_camera.locate import FrameViews, LocatedMarkers, locate_markers
from formulations.cameras.rig import Rig
from formulations.markers.state import MarkerState


def locate_with_reacquisition(
    rig: Rig, frame: FrameViews, views: np.ndarray, state: MarkerState, prediction: np.ndarray,
    gating: PerCameraGating,
) -> tuple[LocatedMarkers, np.ndarray]:
    """Locate the markers from their views, then give single-view markers a second view.

    A two-view point the body rejects (s_n(X) > ``max_pair_shape_mm``) loses the view
    farther from the prediction's image first: two rays meet somewhere whatever they
    carry, and a wrong pair steals a lost marker's detection for good.

    Args:
        rig: The C cameras.
        frame: This frame's detections.
        views: ``(N, C)`` detection per marker and camera, -1 for none.
        state: The markers before this frame (neighbours and their distance statistics).
        prediction: ``(N, 3)`` predicted positions (``state.predict()``).
        gating: tau (``max_reprojection_px``), the largest reprojection error of a kept
            view; s_max (``max_shape_mm``) and ``max_pair_shape_mm``.

    Returns:
        The located markers, and ``(N, C)`` the views they kept (-1 elsewhere).
    """
    tau = gating.max_reprojection_px
    located = locate_markers(rig, *frame.of(views), prediction, tau)
    kept = np.where(located.kept, views, -1)
    shape = _shape(state, located)
    pair = second_views(rig, frame, _without_misshapen_pairs(rig, frame, kept, located, shape, prediction, gating),
                        shape, tau, gating.max_shape_mm)
    if (pair == kept).all():
        return located, kept
    located = locate_markers(rig, *frame.of(pair), prediction, tau)
    return located, np.where(located.kept, pair, -1)


def _without_misshapen_pairs(
    rig: Rig, frame: FrameViews, kept: np.ndarray, located: LocatedMarkers,
    shape: Callable[[np.ndarray, np.ndarray], np.ndarray], prediction: np.ndarray, gating: PerCameraGating,
) -> np.ndarray:
    """``kept`` with one view dropped from the two-view points the body rejects."""
    two = np.flatnonzero(located.n_views == 2)
    deviation = shape(two, located.point[two])
    bad = two[np.isfinite(deviation) & (deviation > gating.max_pair_shape_mm)]
    if len(bad) == 0:
        return kept
    pixels = frame.of(kept[bad])[0]
    off_prediction = np.linalg.norm(rig.project(prediction[bad]) - pixels, axis=2)
    result = kept.copy()
    result[bad, np.nanargmax(off_prediction, axis=1)] = -1
    return result


def second_views(
    rig: Rig, frame: FrameViews, kept: np.ndarray, shape: Callable[[np.ndarray, np.ndarray], np.ndarray],
    max_error_px: float, max_shape_mm: float,
) -> np.ndarray:
    """``kept`` with a second view added where the module doc's search finds one.

    A detection held by a marker with two or more views stays with it; one held as the
    only view of another marker may be taken: that marker's single view then disagreed
    with its other cameras and lost to a pair that agrees with its camera and the body.

    Args:
        shape: s_n(X) for markers ``(K,)`` and points ``(K, 3)``.
    """
    count = (kept >= 0).sum(axis=1)
    single = np.flatnonzero(count == 1)
    marker_parts: list[np.ndarray] = []
    camera_parts: list[np.ndarray] = []
    detection_parts: list[np.ndarray] = []
    for b, found in enumerate(frame.pixels):
        free = np.setdiff1d(np.arange(len(found)), kept[count >= 2, b])
        others = single[kept[single, b] < 0]
        marker_parts.append(np.repeat(others, len(free)))
        camera_parts.append(np.full(len(others) * len(free), b))
        detection_parts.append(np.tile(free, len(others)))
    marker, camera, detection = (np.concatenate(parts) for parts in (marker_parts, camera_parts, detection_parts))
    if len(marker) == 0:
        return kept
    pixels, normalised = frame.of(kept[marker])
    rows, offset = np.arange(len(marker)), _offsets(frame.pixels)[camera] + detection
    pixels[rows, camera] = np.concatenate(frame.pixels)[offset]
    normalised[rows, camera] = np.concatenate(frame.normalised)[offset]
    points = rig.triangulate(normalised)
    error = np.nanmax(rig.errors(points, pixels), axis=1)
    in_front = (rig.depth(points) > 0)[np.isfinite(pixels).all(axis=2)].reshape(-1, 2).all(axis=1)
    accepted = np.flatnonzero((error <= max_error_px) & in_front)
    deviation = shape(marker[accepted], points[accepted])
    accepted, deviation = accepted[deviation <= max_shape_mm], deviation[deviation <= max_shape_mm]
    result = kept.copy()
    for i in accepted[np.argsort(deviation, kind="stable")]:
        n, b, d = marker[i], camera[i], detection[i]
        if (result[n] >= 0).sum() != 1 or result[n, b] >= 0 or (result[count >= 2, b] == d).any():
            continue
        result[result[:, b] == d, b] = -1  # a single-view marker's only view, wrong: it lies on n's pair
        result[n, b] = d
    return result


def _shape(state: MarkerState, located: LocatedMarkers) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """s_n(X) against the neighbours located by two or more cameras (inf if there are none)."""
    anchored = located.n_views >= 2

    def deviation(marker: np.ndarray, points: np.ndarray) -> np.ndarray:
        neighbours = state.neighbours[marker]
        weight = anchored[neighbours] / (state.distance_var[marker] + 1.0)
        distance = np.linalg.norm(points[:, None] - located.point[neighbours], axis=2)
        total = (weight * np.abs(distance - state.distance_mean[marker])).sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(weight.sum(axis=1) > 0, total / weight.sum(axis=1), np.inf)

    return deviation


def _offsets(detections: list[np.ndarray]) -> np.ndarray:
    """Index of each camera's first detection in the concatenation of all cameras'."""
    return np.concatenate([[0], np.cumsum([len(found) for found in detections])])[:-1]
