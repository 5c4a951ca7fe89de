"""Which camera's detections the labels hardly use: a camera moved since it was calibrated.

A camera bumped after calibration still sees every marker, but its detections no longer
agree with the other cameras', so the cross-camera check leaves them out and the labels are
made from the rest (the rig through one camera rolled by 10 degrees: its detections 7-8 %
taken against 97-99 % for the others, RMSE 5.0 mm against 1.4, and nothing said). Per
camera, the share of its detections some marker took; one far under the cameras' median
(``LOW_SHARE`` of it) is named. Clutter and occlusion lower every camera's share alike,
and a camera that sees few markers has few detections, not fewer taken.
"""

from __future__ import annotations

import numpy as np

LOW_SHARE = 0.5  # of the cameras' median share
MIN_DETECTIONS = 20  # fewer, and a camera's share says little


def detections_taken(views: np.ndarray, detections: list[list[np.ndarray]]) -> np.ndarray:
    """``(C,)`` share of each camera's detections a marker took (``views`` ``(F, N, C)``,
    -1 none); NaN for a camera with fewer than ``MIN_DETECTIONS``."""
    found = np.array([[len(frame[c]) for c in range(views.shape[2])] for frame in detections[: len(views)]])
    total = found.sum(axis=0) if len(found) else np.zeros(views.shape[2])
    taken = (views >= 0).sum(axis=(0, 1))
    return np.where(total >= MIN_DETECTIONS, taken / np.maximum(total, 1), np.nan)


def unused_camera_warning(names: list[str], share: np.ndarray) -> str | None:
    """One line naming the cameras whose share is under ``LOW_SHARE`` of the median, or None."""
    judged = np.isfinite(share)
    if judged.sum() < 3:  # with two, which one is off cannot be told
        return None
    median = float(np.median(share[judged]))
    low = [(name, s) for name, s in zip(names, share) if np.isfinite(s) and s < LOW_SHARE * median]
    if not low:
        return None
    listed = ", ".join(f"{name} {s:.0%}" for name, s in low)
    return (f"warning: few of some cameras' detections were taken by a marker ({listed}, against a median of "
            f"{median:.0%} over the cameras): is that camera's calibration off (moved since it was calibrated?), "
            "or its detections filed under another camera?")
