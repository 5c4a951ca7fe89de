"""OpenPose JSON in Pose2Sim's layout: one folder ``camNN_json`` per camera, one file per frame.

Each file is ``{"people": [{"pose_keypoints_2d": [x0, y0, c0, x1, ...]}, ...]}`` with 25 BODY_25B
keypoints; confidence 0 means not detected. INPUT is the folder holding the camera folders, or a
trial folder whose ``pose*`` subfolder does. A file's frame is the last number in its name
(``cam01.0005.json``, OpenPose's ``..._000000000005_keypoints.json``): cameras are joined on it,
not on the files' order, which put a camera that started or dropped a frame later out of step
with the others without a word.
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
    """Per camera (folder name) and frame, the ``(P, 25, 3)`` keypoints of the P people detected
    (none where the camera has no file for the frame), and each frame's number in the file names
    (increasing; numbers no camera has are left out, not filled in), and per camera the numbers it
    has no file for."""

    cameras: list[str]
    people: list[list[np.ndarray]]
    numbers: list[int]
    absent: list[list[int]]

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
    return np.array(read_people(path, body_25b=True)).reshape(-1, len(BODY_25B), 3)


def read_people(path: Path, body_25b: bool = False) -> list[np.ndarray]:
    """Each person's ``(J, 3)`` keypoints (x, y, confidence) in one OpenPose JSON: BODY_25B's 25
    (the layout ``pose`` fits) with ``body_25b``, else any J; a person with no pose keypoints
    (OpenPose writes hand- or face-only people so) is left out.

    Raises:
        InputError: not JSON, no ``people`` list, values not numeric (x, y, confidence) triples
            (or not BODY_25B's count), or a keypoint not finite pixels with a confidence >= 0.
    """
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise InputError(f"{path}: not an OpenPose JSON ({error})") from None
    if not isinstance(data, dict) or not isinstance(data.get("people"), list):
        raise InputError(f"{path}: not an OpenPose JSON (no 'people' list)")
    people = []
    for number, person in enumerate(data["people"]):
        values = person.get("pose_keypoints_2d") if isinstance(person, dict) else None
        if values == []:
            continue
        if not isinstance(values, list) or len(values) % 3 or (body_25b and len(values) != VALUES):
            found = len(values) if isinstance(values, list) else "no"
            expected = f"BODY_25B has {VALUES}" if body_25b else "not (x, y, confidence) triples"
            raise InputError(f"{path}: person {number} has {found} pose_keypoints_2d values, {expected}")
        try:
            keypoints = np.array(values, dtype=float).reshape(-1, 3)
        except (TypeError, ValueError):
            raise InputError(f"{path}: person {number} has non-numeric keypoints") from None
        people.append(_checked(keypoints, path, number, body_25b))
    return people


def _checked(keypoints: np.ndarray, path: Path, number: int, body_25b: bool) -> np.ndarray:
    """A null (read as NaN), infinite or absurd value would reach the geometry as NaN; OpenPose
    writes an undetected keypoint as 0, 0, 0, so say so."""
    bad = np.flatnonzero(~(np.abs(keypoints[:, :2]) <= MAX_PIXEL).all(axis=1) | ~(keypoints[:, 2] >= 0))
    if len(bad):
        name = f"{BODY_25B[bad[0]]} keypoint" if body_25b else f"keypoint {bad[0]}"
        raise InputError(f"{path}: person {number}'s {name} is {keypoints[bad[0]].tolist()}: coordinates must "
                         f"be finite pixels and the confidence a number >= 0 (an undetected keypoint is 0, 0, 0)")
    return keypoints


def write_openpose_file(path: Path, people: np.ndarray) -> None:
    """Write ``(P, 25, 3)`` keypoints as an OpenPose JSON (version 1.3)."""
    persons = [{"person_id": [-1], "pose_keypoints_2d": [round(float(v), 4) for v in person.ravel()]} for person in people]
    path.write_text(json.dumps({"version": 1.3, "people": persons}))


def read_keypoint_frames(input: Path) -> KeypointFrames:
    """Every camera folder's frames, joined on the frame number in the file names: the frames are
    every number any camera has, and a camera without a file for one sees no one in it."""
    folders = camera_folders(input)
    if not folders:
        raise InputError(f"{input}: no per-camera OpenPose folders (camNN_json) found")
    numbered = [numbered_files(folder) for folder in folders]
    numbers = sorted(set().union(*numbered))
    none = np.empty((0, len(BODY_25B), 3))  # as a file with no one in it
    people = [[read_openpose_file(files[n]) if n in files else none for n in numbers] for files in numbered]
    absent = [[n for n in numbers if n not in files] for files in numbered]
    return KeypointFrames([folder.name for folder in folders], people, numbers, absent)


def numbered_files(folder: Path) -> dict[int, Path]:
    """A camera folder's JSON files by frame number, the last run of digits in the name.

    Raises:
        InputError: no JSON file, a file whose name has no number, or two files of one number
            (their order would have to be guessed).
    """
    files = numbered_paths(sorted(folder.glob("*.json")), folder)
    if not files:
        raise InputError(f"{folder}: no OpenPose .json file")
    return files


def numbered_paths(paths: list[Path], folder: Path) -> dict[int, Path]:
    """``paths`` (one camera's frames, in ``folder``) by the frame number in their names.

    Raises:
        InputError: a name without a number, or two of one number.
    """
    files: dict[int, Path] = {}
    for path in paths:
        number = _number(path.stem)
        if number is None:
            raise InputError(f"{path}: no frame number in the file name (OpenPose numbers them: "
                             f"cam01.0005.json, or ..._000000000005_keypoints.json)")
        if number in files:
            raise InputError(f"{folder}: {files[number].name} and {path.name} are both frame {number}")
        files[number] = path
    return files


def missing_frames_warning(frames: KeypointFrames) -> str | None:
    """A line naming the cameras without a file for some of the frames: they are fitted without
    that camera there, which reads differently from a camera that saw no one."""
    lacking = []
    for camera, absent in zip(frames.cameras, frames.absent):
        if absent:
            listed = ", ".join(map(str, absent[:8])) + (" ..." if len(absent) > 8 else "")
            lacking.append(f"{camera} has no file for {len(absent)} ({listed})")
    if not lacking:
        return None
    return (f"warning: of the {len(frames.numbers)} frames numbered in the file names, {'; '.join(lacking)}: "
            "fitted without that camera there")


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
