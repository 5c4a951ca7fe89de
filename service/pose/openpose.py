"""OpenPose JSON in Pose2Sim's layout: one folder ``camNN_json`` per camera, one file per frame.

Each file is ``{"people": [{"pose_keypoints_2d": [x0, y0, c0, x1, ...]}, ...]}`` with 25 BODY_25B
keypoints; confidence 0 means not detected. INPUT is the folder holding the camera folders, or a
trial folder whose ``pose*`` subfolder does.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from formulations.cameras.camera import Camera
from formulations.pose.keypoints import BODY_25B
from service.errors import InputError

VALUES = 3 * len(BODY_25B)
MAX_PIXEL = 1e9  # as a capture's coordinates (``service.capture.checks``): larger overflow in the geometry


@dataclass(frozen=True)
class KeypointFrames:
    """Per camera (folder name) and frame, the ``(P, 25, 3)`` keypoints of the P people detected."""

    cameras: list[str]
    people: list[list[np.ndarray]]

    @property
    def frames(self) -> int:
        return len(self.people[0])


def camera_folders(input: Path) -> list[Path]:
    """The ``*_json`` folders in ``input`` or in its ``pose*`` subfolders, sorted by name."""
    if not input.is_dir():
        raise InputError(f"{input}: not a folder")
    folders = sorted(p for p in input.glob("*_json") if p.is_dir())
    if not folders:
        folders = sorted(p for p in input.glob("pose*/*_json") if p.is_dir())
    return folders


def read_openpose_file(path: Path) -> np.ndarray:
    """``(P, 25, 3)`` keypoints of one frame; a file that is not OpenPose BODY_25B is an InputError."""
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise InputError(f"{path}: not an OpenPose JSON ({error})") from None
    if not isinstance(data, dict) or not isinstance(data.get("people"), list):
        raise InputError(f"{path}: not an OpenPose JSON (no 'people' list)")
    people = []
    for number, person in enumerate(data["people"]):
        values = person.get("pose_keypoints_2d") if isinstance(person, dict) else None
        if values == []:  # OpenPose writes a person with hand or face keypoints only like this
            continue
        if not isinstance(values, list) or len(values) != VALUES:
            found = len(values) if isinstance(values, list) else "no"
            raise InputError(f"{path}: person {number} has {found} pose_keypoints_2d values, BODY_25B has {VALUES}")
        try:
            keypoints = np.array(values, dtype=float).reshape(len(BODY_25B), 3)
        except (TypeError, ValueError):
            raise InputError(f"{path}: person {number} has non-numeric keypoints") from None
        people.append(_checked(keypoints, path, number))
    return np.array(people).reshape(-1, len(BODY_25B), 3)


def _checked(keypoints: np.ndarray, path: Path, number: int) -> np.ndarray:
    """A null (read as NaN), infinite or absurd value would reach the particle filter's
    energy as NaN; OpenPose writes an undetected keypoint as 0, 0, 0, so say so."""
    bad = np.flatnonzero(~(np.abs(keypoints[:, :2]) <= MAX_PIXEL).all(axis=1) | ~(keypoints[:, 2] >= 0))
    if len(bad):
        name, value = BODY_25B[bad[0]], keypoints[bad[0]].tolist()
        raise InputError(f"{path}: person {number}'s {name} keypoint is {value}: coordinates must be finite pixels "
                         f"and the confidence a number >= 0 (an undetected keypoint is 0, 0, 0)")
    return keypoints


def write_openpose_file(path: Path, people: np.ndarray) -> None:
    """Write ``(P, 25, 3)`` keypoints as an OpenPose JSON (version 1.3)."""
    persons = [{"person_id": [-1], "pose_keypoints_2d": [round(float(v), 4) for v in person.ravel()]} for person in people]
    path.write_text(json.dumps({"version": 1.3, "people": persons}))


def read_keypoint_frames(input: Path) -> KeypointFrames:
    """Every camera folder's frames; the cameras must have as many frames each."""
    folders = camera_folders(input)
    if not folders:
        raise InputError(f"{input}: no per-camera OpenPose folders (camNN_json) found")
    people = [[read_openpose_file(path) for path in sorted(folder.glob("*.json"))] for folder in folders]
    counts = {folder.name: len(frames) for folder, frames in zip(folders, people)}
    if len(set(counts.values())) != 1 or not min(counts.values()):
        listed = ", ".join(f"{name} {count}" for name, count in counts.items())
        raise InputError(f"{input}: the cameras have different (or zero) frame counts: {listed}")
    return KeypointFrames([folder.name for folder in folders], people)


def _number(name: str) -> int | None:
    digits = re.findall(r"\d+", name)
    return int(digits[-1]) if digits else None


def match_cameras(folders: list[str], cameras: list[Camera], calibration: Path) -> list[Camera]:
    """The calibrated camera of each folder, matched by the number in the names (``cam01_json`` is
    ``cam_01``; Pose2Sim's convention), else by equal names with ``_json`` removed."""
    chosen = []
    for folder in folders:
        stem = folder.removesuffix("_json")
        found = [c for c in cameras if c.name == stem] or [
            c for c in cameras if _number(folder) is not None and _number(c.name) == _number(folder)]
        if len(found) != 1:
            names = ", ".join(c.name for c in cameras)
            raise InputError(f"{calibration}: no camera for folder {folder} (the calibration has {names})")
        chosen.append(found[0])
    return chosen
