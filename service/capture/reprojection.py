"""Does the labeled first frame land on frame 0's detections, camera by camera?

In camera mode the user's labeled frame 0 (3D, world unit) and the calibration meet only
through projection. A calibration in metres read as mm, detections given as (y, x), an ``R``
given camera-to-world or a camera's detections filed under another camera all label
"successfully": the markers are simply never measured (100 % occluded, every window
integral). Frame 0 shows it at once: each marker's projection should sit on a detection.

Per camera, the offset is a low quantile (``QUANTILE``) of the distance from each marker's
projection (in front of the camera and on its sensor) to the nearest frame-0 detection: a
marker that camera does not see lands on another's detection or on none, so a low quantile
stays small while three markers in four are hidden; a wrong camera puts most projections far
from every detection (tens of pixels and more among 40 markers in a full-HD image).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from formulations.cameras.camera import Camera

OFF_PX = 10.0  # a right camera's markers sit within a few pixels (noise, centroid bias) of a detection
QUANTILE = 0.25  # of the markers' distances: judged on the best-seen quarter


def frame0_distances(cameras: list[Camera], first_frame: np.ndarray,
                     detections: list[np.ndarray]) -> list[np.ndarray | None]:
    """Per camera, each labeled marker's distance (px) from its projection (in front of the
    camera and on its sensor) to the nearest frame-0 detection; None where the camera has no
    detection or nothing is labeled, empty where no marker projects onto its sensor."""
    known = first_frame[np.isfinite(first_frame).all(axis=1)]
    distances: list[np.ndarray | None] = []
    for camera, pixels in zip(cameras, detections):
        if not len(pixels) or not len(known):
            distances.append(None)
            continue
        projected = camera.project(known[(known @ camera.R.T + camera.t)[:, 2] > 0])
        distances.append(cKDTree(pixels).query(projected[camera.in_image(projected)])[0] if len(projected) else
                         np.zeros(0))
    return distances


def frame0_offsets(distances: list[np.ndarray | None]) -> list[float | None]:
    """Per camera the frame-0 offset in pixels (module doc) of ``frame0_distances``; None where
    nothing can be judged, inf when detections exist but no marker projects onto the sensor."""
    return [None if d is None else float(np.quantile(d, QUANTILE)) if len(d) else float("inf") for d in distances]


def frame0_problem(cameras: list[Camera], offsets: list[float | None]) -> tuple[bool, str] | None:
    """``(every camera is off, the line)`` when some camera's offset exceeds ``OFF_PX``, else None."""
    judged = [(camera.name, off) for camera, off in zip(cameras, offsets) if off is not None]
    off = [(name, value) for name, value in judged if value > OFF_PX]
    if not off:
        return None
    listed = ", ".join(f"{name}: {'no marker on its sensor' if value == np.inf else f'{value:.0f} px'}" for name, value in off)
    if len(off) == len(judged):
        return True, (f"the labeled first frame does not land on frame 0's detections in any camera ({listed}): are "
                      "first_frame and the calibration in one unit (the document's \"units\"), and the detections "
                      "(x, y) pixels?")
    return False, (f"warning: the labeled first frame lands off frame 0's detections in {len(off)} of {len(judged)} "
                   f"cameras ({listed}; others within {OFF_PX:g} px): check that camera's R, t and image size, and "
                   "which detections are filed under it")


RAYLEIGH_MEDIAN = 1.1774  # median of |e| for a 2D error e with sd sigma per axis: sqrt(2 ln 2) sigma


def frame0_pixel_sigma(distances: list[np.ndarray | None]) -> float | None:
    """Per-axis sd (px) of a detection about the labeled first frame's projection, from
    ``frame0_distances`` within ``OFF_PX`` (the others are markers that camera does not see);
    None when fewer than 3. Calibration error is in it, as it should be: the cross-camera
    matcher's gates must pass the detections as this calibration projects them."""
    pooled = np.concatenate([d[d <= OFF_PX] for d in distances if d is not None] or [np.zeros(0)])
    return float(np.median(pooled)) / RAYLEIGH_MEDIAN if len(pooled) >= 3 else None
