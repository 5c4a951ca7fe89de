"""Grey histograms of detection boxes from a folder of frames (Jiang Sec. IV-A: 64 bins).

Frames are the MOTChallenge ``img1`` layout: ``000001.jpg``, ``000002.jpg``, ... numbered as
the detections' frames (the extension from ``seqinfo.ini``, else whatever the folder holds
for the first detection's frame). Each box's histogram is
taken by OpenCV on the grey frame, clipped to the image, and normalised to sum 1.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from service.boxes.detections import BoxDetections
from service.errors import InputError

BINS = 64


def box_histograms(detections: BoxDetections, folder: Path, extension: str | None = None) -> np.ndarray:
    """``(K, 64)`` normalised grey histogram of every detection box."""
    if not folder.is_dir():
        raise InputError(f"{folder}: no such folder of frames")
    ext = extension or _extension(folder, _first(detections))
    histograms = np.zeros((len(detections.frame), BINS))
    for f in np.unique(detections.frame):
        image = _frame(folder / f"{int(f):06d}{ext}")
        for k in np.flatnonzero(detections.frame == f):
            histograms[k] = grey_histogram(image, detections.box[k])
    return histograms


def frame_size(detections: BoxDetections, folder: Path, extension: str | None = None) -> tuple[float, float]:
    """``(width, height)`` in pixels of the first detection's frame."""
    first = _first(detections)
    image = _frame(folder / f"{first:06d}{extension or _extension(folder, first)}")
    return float(image.shape[1]), float(image.shape[0])


def _frame(path: Path) -> np.ndarray:
    """The grey frame; a missing one is named (not left to OpenCV's warning on stderr)."""
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) if path.is_file() else None
    if image is None:
        raise InputError(f"{path}: missing or not an image (frames are named as the detections' frame numbers, "
                         f"000001{path.suffix}, ...)")
    return image


def grey_histogram(image: np.ndarray, ltwh: np.ndarray) -> np.ndarray:
    """64-bin histogram of the grey pixels inside a box, normalised (uniform for an empty crop)."""
    height, width = image.shape[:2]
    x1, y1 = int(max(0, np.floor(ltwh[0]))), int(max(0, np.floor(ltwh[1])))
    x2, y2 = int(min(width, np.ceil(ltwh[0] + ltwh[2]))), int(min(height, np.ceil(ltwh[1] + ltwh[3])))
    if x2 <= x1 or y2 <= y1:
        return np.full(BINS, 1.0 / BINS)
    counts = cv2.calcHist([np.ascontiguousarray(image[y1:y2, x1:x2])], [0], None, [BINS], [0, 256]).ravel()
    return counts / counts.sum()


def _first(detections: BoxDetections) -> int:
    return int(detections.frame.min()) if len(detections.frame) else 1


def _extension(folder: Path, first: int) -> str:
    if (folder / f"{first:06d}.jpg").exists():
        return ".jpg"
    found = sorted(folder.glob(f"{first:06d}.*"))
    if not found:
        raise InputError(f"{folder}: no frame {first:06d}.* in the folder (the first detection's frame)")
    return found[0].suffix
