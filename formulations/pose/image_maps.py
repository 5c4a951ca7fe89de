"""The two bottom-up image maps of Fig. 2, with OpenCV.

Edges: Canny edges, then each pixel's distance d to the nearest edge (``cv2.distanceTransform``)
becomes the proximity p^e = exp(-d^2 / (2 s^2)) in [0, 1] (the paper thresholds edges and
smooths them with a Gaussian; the distance map gives the same fall-off without a kernel size).
Foreground: thresholded background subtraction, |I - I_background| > threshold on any channel,
opened by a 3 x 3 kernel to drop isolated noise pixels; 1 on the foreground, 0 elsewhere.
"""

from __future__ import annotations

import cv2
import numpy as np

from formulations.pose.rotation import Array


def _gray(image: Array) -> Array:
    gray: Array = image if image.ndim == 2 else np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), dtype=float)
    return gray


def edge_proximity(image: Array, scale: float = 4.0, low: int = 50, high: int = 150) -> Array:
    """``(H, W)`` p^e of an 8-bit image; ``scale`` s in pixels."""
    edges = cv2.Canny(_gray(image).astype(np.uint8), low, high)
    distance = cv2.distanceTransform(np.where(edges > 0, 0, 255).astype(np.uint8), cv2.DIST_L2, 3)
    proximity: Array = np.exp(-(distance.astype(float) ** 2) / (2.0 * scale ** 2))
    return proximity


def foreground_mask(image: Array, background: Array, threshold: int = 30) -> Array:
    """``(H, W)`` p^r of an 8-bit image against a reference image with no one in it."""
    difference = cv2.absdiff(image.astype(np.uint8), background.astype(np.uint8))
    if difference.ndim == 3:
        difference = difference.max(axis=2)
    mask = cv2.morphologyEx((difference > threshold).astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    foreground: Array = mask.astype(float)
    return foreground
