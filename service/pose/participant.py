"""Which detected person is the participant, in every camera and frame.

First frame: every combination of one person per camera (the four most confident people of
each camera) is triangulated (DLT over the cameras, keypoints with confidence above
``CONFIDENT``), and the combination whose triangulation reprojects with the smallest median
error wins: the participant is the person the cameras agree on, so a bystander seen by one
or two cameras is left out. Where several people agree equally well (two participants), the
first in this order is taken; a camera whose chosen person still reprojects worse than
``GATE_FRACTION`` of the image height is given no one.
Later frames: in each camera, the person nearest (median keypoint distance) to the
participant's last detection in that camera, if within the gate; failing that (or in a camera
that has not seen the participant yet), the person nearest the reprojection of what the other
cameras agreed on in this frame; else no one in that camera and frame.
"""

from __future__ import annotations

import itertools

import numpy as np

from formulations.cameras.rig import Rig

CONFIDENT = 0.3
GATE_FRACTION = 0.1
MOST_PEOPLE = 4


def triangulate(rig: Rig, detections: np.ndarray) -> np.ndarray:
    """``(K, 3)`` DLT points of ``(C, K, 3)`` detections; NaN where fewer than two cameras are confident."""
    pixels = np.where((detections[..., 2:] > CONFIDENT), detections[..., :2], np.nan).transpose(1, 0, 2)
    return rig.triangulate(rig.undistort(pixels))


def _agreement(rig: Rig, detections: np.ndarray) -> np.ndarray:
    """``(C,)`` median reprojection error per camera of the triangulated keypoints; inf if nothing to check."""
    points = triangulate(rig, detections)
    seen = np.isfinite(points).all(axis=1)
    errors = np.full(len(detections), np.inf)
    if seen.any():
        reprojected = rig.project(points[seen]).transpose(1, 0, 2)
        for c in range(len(detections)):
            confident = detections[c, seen, 2] > CONFIDENT
            if confident.any():
                errors[c] = np.median(np.linalg.norm(reprojected[c, confident] - detections[c, seen][confident, :2], axis=1))
    return errors


def _gate(rig: Rig) -> np.ndarray:
    gate: np.ndarray = GATE_FRACTION * rig.image_size[:, 1]
    return gate


def first_choice(rig: Rig, people: list[np.ndarray]) -> list[int | None]:
    """The participant's index in each camera's ``(P, 25, 3)`` people at the first frame."""
    options = [list(np.argsort(-p[:, :, 2].sum(axis=1))[:MOST_PEOPLE]) if len(p) else [None] for p in people]
    best: tuple[float, list[int | None]] = (np.inf, [None] * len(people))
    empty = np.zeros(people[0].shape[1:] if len(people[0]) else (25, 3))
    for combination in itertools.product(*options):
        detections = np.stack([empty if i is None else p[i] for p, i in zip(people, combination)])
        errors = _agreement(rig, detections)
        score = float(np.median(errors[np.isfinite(errors)])) if np.isfinite(errors).sum() >= 2 else np.inf
        if score < best[0]:
            chosen = [i if errors[c] <= _gate(rig)[c] else None for c, i in enumerate(combination)]
            best = (score, chosen)
    return best[1]


def choose_participant(rig: Rig, people: list[list[np.ndarray]]) -> np.ndarray:
    """``(F, C, 25, 3)`` the participant's keypoints per frame and camera (zeros where no one)."""
    cameras, frames = len(people), len(people[0])
    chosen = np.zeros((frames, cameras, 25, 3))
    start = next((f for f in range(frames) if sum(len(people[c][f]) > 0 for c in range(cameras)) >= 2), None)
    if start is None:
        return chosen
    last: list[np.ndarray | None] = [None] * cameras
    for c, index in enumerate(first_choice(rig, [people[c][start] for c in range(cameras)])):
        if index is not None:
            chosen[start, c] = last[c] = people[c][start][index]
    for f in range(start + 1, frames):
        found = [_follow(rig, people[c][f], last[c], chosen[f], c) for c in range(cameras)]
        for c in [c for c in range(cameras) if found[c] is None]:  # lost or never seen: the others' reprojection
            found[c] = _follow(rig, people[c][f], _reprojected(rig, chosen[f], c), chosen[f], c)
        last = [new if new is not None else old for new, old in zip(found, last)]
    return chosen


def _follow(rig: Rig, people: np.ndarray, reference: np.ndarray | None, chosen: np.ndarray, c: int) -> np.ndarray | None:
    """Put the person of ``people`` nearest ``reference`` into ``chosen[c]`` if within the gate; return it."""
    if reference is None or not len(people):
        return None
    distances = [_distance(reference, person) for person in people]
    nearest = int(np.argmin(distances))
    if distances[nearest] > _gate(rig)[c]:
        return None
    chosen[c] = people[nearest]
    return chosen[c].copy()


def _reprojected(rig: Rig, detections: np.ndarray, c: int) -> np.ndarray | None:
    """``(25, 3)`` the other cameras' triangulated keypoints seen from camera c (confidence 1), or None."""
    points = triangulate(rig, detections)
    seen = np.isfinite(points).all(axis=1)
    if seen.sum() < 3:
        return None
    reference = np.zeros((len(points), 3))
    reference[seen, :2] = rig.project(points[seen])[:, c]
    reference[seen, 2] = 1.0
    return reference


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    both = (a[:, 2] > 0) & (b[:, 2] > 0)
    return float(np.median(np.linalg.norm(a[both, :2] - b[both, :2], axis=1))) if both.any() else np.inf
