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


def frame0_offsets(cameras: list[Camera], first_frame: np.ndarray, detections: list[np.ndarray]) -> list[float | None]:
    """Per camera the frame-0 offset in pixels (module doc); None where nothing can be judged
    (no detection, or no labeled marker in front of it and on its sensor), inf when
    detections exist but no marker projects onto the sensor."""
    known = first_frame[np.isfinite(first_frame).all(axis=1)]
    offsets: list[float | None] = []
    for camera, pixels in zip(cameras, detections):
        if not len(pixels) or not len(known):
            offsets.append(None)
            continue
        ahead = known[(known @ camera.R.T + camera.t)[:, 2] > 0]
        projected = camera.project(ahead)
        projected = projected[camera.in_image(projected)]
        if not len(projected):
            offsets.append(float("inf"))
            continue
        distance = cKDTree(pixels).query(projected)[0]
        offsets.append(float(np.quantile(distance, QUANTILE)))
    return offsets


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


def frame0_pixel_sigma(cameras: list[Camera], first_frame: np.ndarray, detections: list[np.ndarray]) -> float | None:
    """Per-axis sd (px) of a detection about the labeled first frame's projection, over every
    camera and marker whose projection has a detection within ``OFF_PX`` (the others are not
    seen there); None when fewer than 3 do. Calibration error is in it, as it should be: the
    cross-camera matcher's gates must pass the detections as this calibration projects them."""
    known = first_frame[np.isfinite(first_frame).all(axis=1)]
    near: list[np.ndarray] = []
    for camera, pixels in zip(cameras, detections):
        ahead = known[(known @ camera.R.T + camera.t)[:, 2] > 0]
        if not len(pixels) or not len(ahead):
            continue
        distance = cKDTree(pixels).query(camera.project(ahead))[0]
        near.append(distance[distance <= OFF_PX])
    pooled = np.concatenate(near) if near else np.zeros(0)
    return float(np.median(pooled)) / RAYLEIGH_MEDIAN if len(pooled) >= 3 else None
