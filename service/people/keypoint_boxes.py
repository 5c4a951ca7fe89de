"""A person's box from body keypoints: the keypoints' extent, padded to the body's outline.

Keypoints are joints, inside the body: the box through the detected ones (confidence
above ``min_confidence``) is widened by ``margin`` of its height on every side (the top
of the head lies above the eyes and ears, the hands beyond the wrists). The padding is
what lets a person cut by the image border show as a truncated box: its keypoints stop
at the border, and the padded box reaches beyond it.
"""

from __future__ import annotations

import numpy as np

from service.boxes.detections import BoxDetections


def keypoint_box(keypoints: np.ndarray, min_confidence: float = 0.1, margin: float = 0.1) -> np.ndarray | None:
    """``(4,)`` left, top, width, height around ``(J, 3)`` keypoints, None with fewer than 2 detected."""
    seen = keypoints[keypoints[:, 2] > min_confidence, :2]
    if len(seen) < 2:
        return None
    low, high = seen.min(axis=0), seen.max(axis=0)
    pad = margin * (high[1] - low[1])
    return np.array([low[0] - pad, low[1] - pad, high[0] - low[0] + 2 * pad, high[1] - low[1] + 2 * pad])


def person_boxes(
    frames: list[list[np.ndarray]], image_size: tuple[float, float], min_keypoints: int = 6,
    min_confidence: float = 0.1, margin: float = 0.1,
) -> BoxDetections:
    """One camera's people as box detections (frames from 1, MOTChallenge style).

    A person needs ``min_keypoints`` detected keypoints to count: OpenPose also reports
    fragments (a hand, a head) that are not a view of anyone. The confidence of a box is
    the mean confidence of its person's keypoints.
    """
    rows: list[tuple[int, np.ndarray, float]] = []
    for f, people in enumerate(frames, start=1):
        for keypoints in people:
            if (keypoints[:, 2] > min_confidence).sum() < min_keypoints:
                continue
            box = keypoint_box(keypoints, min_confidence, margin)
            if box is not None:
                rows.append((f, box, float(keypoints[:, 2].mean())))
    return BoxDetections(
        frame=np.array([r[0] for r in rows], dtype=int), box=np.array([r[1] for r in rows]).reshape(-1, 4),
        confidence=np.array([r[2] for r in rows]), n_frames=len(frames), image_size=image_size,
    )
