"""Which of a camera's person tracks is which participant, from the participants' 3D keypoints.

Per-camera tracks have identities of their own; the participants have names across
cameras only in 3D (Pose2Sim triangulates each participant's keypoints into a TRC).
Each participant's 3D keypoints are projected into the camera and boxed like detected
keypoints (``keypoint_box``). A track is that participant's when its boxes overlap the
projected ones by a mean IoU of at least ``min_iou`` over the track's frames (the best
such participant); a track overlapping none (a bystander) is nobody's. The 3D only
names tracks: the boxes that are measured are the tracked ones.
"""

from __future__ import annotations

import numpy as np

from formulations.boxes.geometry import area, corners
from formulations.cameras.camera import Camera
from service.boxes.detections import BoxTracks
from service.people.keypoint_boxes import keypoint_box


def projected_boxes(keypoints_3d: np.ndarray, camera: Camera, margin: float = 0.1) -> np.ndarray:
    """``(F, 4)`` box of ``(F, J, 3)`` world keypoints seen from ``camera``; NaN where fewer than 2 project.

    Keypoints behind the camera, outside its image or NaN do not count.
    """
    frames, joints, _ = keypoints_3d.shape
    flat = keypoints_3d.reshape(-1, 3)
    known = np.isfinite(flat).all(axis=1) & (np.nan_to_num(flat) @ camera.R[2] + camera.t[2] > 0)
    pixels = np.full((len(flat), 2), np.nan)
    pixels[known] = camera.project(flat[known])
    seen = camera.in_image(pixels).astype(float).reshape(frames, joints, 1)
    boxes = np.full((frames, 4), np.nan)
    for f, (points, conf) in enumerate(zip(pixels.reshape(frames, joints, 2), seen)):
        box = keypoint_box(np.concatenate([np.nan_to_num(points), conf], axis=1), 0.5, margin)
        if box is not None:
            boxes[f] = box
    return boxes


def participant_boxes(tracks: BoxTracks, reference: np.ndarray, min_iou: float = 0.3) -> np.ndarray:
    """``(P, F, 4)`` each participant's tracked box per frame in this camera, NaN where none.

    ``reference`` is ``(P, F, 4)``, the participants' projected boxes (``projected_boxes``).
    Where two tracks of one participant share a frame, the one overlapping its reference
    more is kept.
    """
    n_people, n_frames, _ = reference.shape
    rows = np.arange(len(tracks.frame))
    overlap = np.zeros((n_people, len(rows)))
    for p in range(n_people):
        ref = reference[p, tracks.frame - 1]
        known = np.isfinite(ref).all(axis=1)
        overlap[p, known] = _paired_iou(corners(ref[known]), corners(tracks.box[known]))
    owner = np.full(len(rows), -1)
    for track in np.unique(tracks.track_id):
        mine = tracks.track_id == track
        mean = overlap[:, mine].mean(axis=1)
        if mean.max() >= min_iou:
            owner[mine] = int(np.argmax(mean))
    boxes = np.full((n_people, n_frames, 4), np.nan)
    best = np.zeros((n_people, n_frames))
    for row in rows[owner >= 0]:
        p, f = owner[row], tracks.frame[row] - 1
        if overlap[p, row] >= best[p, f]:
            boxes[p, f], best[p, f] = tracks.box[row], overlap[p, row]
    return boxes


def _paired_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(K,)`` IoU of box a_k with box b_k (corners)."""
    low, high = np.maximum(a[:, :2], b[:, :2]), np.minimum(a[:, 2:], b[:, 2:])
    common = np.prod(np.clip(high - low, 0.0, None), axis=1)
    union = area(a) + area(b) - common
    return np.where(union > 0, common / np.where(union > 0, union, 1.0), 0.0)
