"""The detections the labeled first frame's markers took, camera by camera.

The window LP starts after frame 0: the user labeled it in 3D, so no window chooses its
views. Without them every camera looks blind in frame 0, and whatever reads the views there
(the best view, which carries its frame-0 choice into later frames) sees an arbitrary camera.
Here each camera's frame-0 detections are assigned to the labeled markers' projections, as
the per-camera guide assigns a frame's detections to its predictions: one-to-one
(``assign_within_gates``), distances in mm at the marker's depth (``image_distances``), a
marker missing in that camera where no detection lies within the gate.
"""

from __future__ import annotations

import numpy as np

from formulations.cameras.per_camera.guide import image_distances
from formulations.cameras.per_camera.locate import FrameViews
from formulations.cameras.rig import Rig
from formulations.markers.guide import assign_within_gates


def first_frame_views(rig: Rig, positions: np.ndarray, frame: FrameViews, radius_mm: float) -> np.ndarray:
    """``(N, C)`` frame-0 detection each labeled marker took in each camera, -1 none.

    Args:
        rig: The C cameras.
        positions: ``(N, 3)`` labeled positions, NaN where a marker is not labeled (it takes none).
        frame: Frame 0's detections, with their normalised coordinates.
        radius_mm: Gate around each projection, mm at the marker's depth; also the cost of a
            miss, so within the gate a marker takes a detection rather than none.
    """
    n = len(positions)
    image, depth = rig.image_plane(np.asarray(positions, dtype=float))
    gate = np.full(n, radius_mm)
    columns = [
        assign_within_gates(image_distances(image[c], depth[c], found), gate, radius_mm) if len(found)
        else np.full(n, -1)
        for c, found in enumerate(frame.normalised)
    ]
    return np.stack(columns, axis=1) if columns else np.full((n, 0), -1)
