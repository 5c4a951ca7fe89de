"""Warnings about detections that do not fit the image they are said to come from.

The box costs are in pixels and objects leave at the image border (``formulations.boxes
.lifecycle``), so an image size that is wrong (a seqinfo.ini of another camera) ends
objects inside the real image, and boxes in normalised coordinates (0..1, as many
detectors write them) move a fraction of a pixel per frame against gates of pixels: both
track worse without failing, so both are said.
"""

from __future__ import annotations

import numpy as np

from service.boxes.detections import BoxDetections

TINY_BOXES = 2.0  # pixels: no camera's detections are all narrower and lower than this


def outside_image_warning(detections: BoxDetections, size: tuple[float, float], source: str) -> str | None:
    """A line when some boxes lie wholly outside the ``(width, height)`` image of ``source``."""
    box = detections.box
    right, bottom = box[:, 0] + box[:, 2], box[:, 1] + box[:, 3]
    outside = (box[:, 0] >= size[0]) | (box[:, 1] >= size[1]) | (right <= 0) | (bottom <= 0)
    if not outside.any():
        return None
    return (f"warning: {int(outside.sum())} of {len(box)} detections lie wholly outside the {size[0]:g} x {size[1]:g} "
            f"image of {source} (boxes reach x = {right.max():g}, y = {bottom.max():g}); objects end at its border: "
            "is the image size right?")


def normalised_warning(detections: BoxDetections) -> str | None:
    """A line when every box is smaller than ``TINY_BOXES`` pixels: normalised coordinates."""
    if not len(detections.box) or np.abs(detections.box[:, 2:]).max() >= TINY_BOXES:
        return None
    return (f"warning: every box is under {TINY_BOXES:g} pixels wide and high: normalised coordinates? The tracking "
            "costs are in pixels; multiply left, top, width and height by the image's width and height")
