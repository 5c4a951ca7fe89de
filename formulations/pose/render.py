"""Silhouettes of the cone model drawn into an image: the synthetic input of the edge and foreground tests.

Each cone is drawn as the quadrilateral between its projected occluding contours (``cone_sites``
with one site at each end) capped by a disc at each end of its projected radius.
"""

from __future__ import annotations

import cv2
import numpy as np

from formulations.cameras.camera import Camera
from formulations.pose.body import BodyModel
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.rotation import Array


def render_silhouette(model: BodyModel, configuration: Array, camera: Camera, image: Array, shade: int = 200) -> Array:
    """``image`` (8-bit, ``camera``'s size) with the body at ``configuration`` drawn over it in ``shade``."""
    posed = forward_kinematics(model, configuration[None])
    drawn = image.copy()
    centre = camera.centre
    for cone in model.cones:
        a, b = posed.positions[0, cone.start], posed.positions[0, cone.end]
        normal = np.cross(b - a, 0.5 * (a + b) - centre)
        normal /= np.linalg.norm(normal) or 1.0
        corners = np.array([a - cone.radii[0] * normal, b - cone.radii[1] * normal, b + cone.radii[1] * normal,
                            a + cone.radii[0] * normal])
        pixels = camera.project(corners)
        cv2.fillConvexPoly(drawn, np.rint(pixels).astype(np.int32), shade)
        for end, side in ((0, 3), (1, 2)):
            centre_pixel = 0.5 * (pixels[end] + pixels[side])
            radius = int(round(0.5 * float(np.linalg.norm(pixels[end] - pixels[side]))))
            cv2.circle(drawn, tuple(int(v) for v in np.rint(centre_pixel)), radius, shade, -1)
    return drawn
