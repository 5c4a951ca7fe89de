"""OpenPose's per-frame JSON: ``people[i].pose_keypoints_2d`` = (x, y, confidence) per keypoint.

One folder per camera, one file per frame (``<name>.<frame>.json`` or
``<name>_<frame>_keypoints.json``; frames in the order of the number in the file names,
``pose.openpose.numbered_files``: sorted names put ``cam.10.json`` before ``cam.9.json``), any
keypoint layout (BODY_25B has 25 keypoints; a confidence of 0 means not detected).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from service.errors import InputError
from service.pose.openpose import numbered_files, read_people


def read_openpose_folder(folder: Path) -> tuple[list[int], list[list[np.ndarray]]]:
    """The frame numbers in the file names, and per frame one ``(J, 3)`` array (x, y,
    confidence) per detected person.

    Raises:
        InputError: a missing folder, no JSON file in it, a file name without a frame number
            or two of one number, a file that is not OpenPose JSON, or keypoints not finite
            (x, y, confidence) triples (``read_people``).
    """
    if not folder.is_dir():
        raise InputError(f"{folder}: no such folder of OpenPose JSON files")
    files = numbered_files(folder)
    numbers = sorted(files)
    return numbers, [read_people(files[number]) for number in numbers]
