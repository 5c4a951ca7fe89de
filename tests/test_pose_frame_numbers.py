"""``pose`` joins the cameras' OpenPose files on the frame number in their names, and keeps it.

The files used to be paired by their sorted order: a camera whose files started five frames later
(or that missed a different frame than the others) was fitted against the others' frames five
apart, exit 0 and no word. Built here from the Pose2Sim demo's real BODY_25B files."""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from test_pose_cli import CALIBRATION, one_line_error, run_inline

from service.io.formats.trc import read_trc
from service.pose.openpose import read_keypoint_frames, read_openpose_file

DEMO = DATA / "multicam2d_pose2sim_demo" / "balancing_trial_1person" / "pose_openpose_body25b"
pytestmark = pytest.mark.skipif(not DEMO.exists(), reason="Pose2Sim demo keypoints not present")
CAMERAS = ("01", "02", "03", "04")
QUICK = ("--particles", "20", "--layers", "2")


def demo_file(camera: str, number: int) -> Path:
    return DEMO / f"cam{camera}_json" / f"cam{camera}.{number:04d}.json"


def pose2sim_name(camera: str, number: int) -> str:
    return f"cam{camera}.{number:04d}.json"


def openpose_name(camera: str, number: int) -> str:
    return f"cam{camera}_{number:012d}_keypoints.json"


def demo_take(folder: Path, numbers: dict[str, Iterable[int]], name: Callable[[str, int], str] = pose2sim_name) -> Path:
    """A take of the demo's files: camera -> the frame numbers it has, each file named ``name(camera, n)``."""
    for camera, frames in numbers.items():
        (folder / f"cam{camera}_json").mkdir(parents=True)
        for number in frames:
            shutil.copy(demo_file(camera, number), folder / f"cam{camera}_json" / name(camera, number))
    return folder


def shifted_take(folder: Path) -> Path:
    """Cameras 1, 3 and 4 at frames 0-9; camera 2 at 5-14, in OpenPose's own file names (as many files each)."""
    take = demo_take(folder, {c: range(10) for c in CAMERAS if c != "02"})
    demo_take(take, {"02": range(5, 15)}, openpose_name)
    return take


def trc_rows(path: Path) -> list[tuple[str, str]]:
    """Each row's Frame# and Time cells as written."""
    rows = [line.split("\t") for line in path.read_text().splitlines()[6:] if line.strip()]
    return [(row[0], row[1]) for row in rows]


def test_a_camera_starting_five_frames_later_is_joined_on_the_frame_number(tmp_path: Path) -> None:
    shifted = read_keypoint_frames(shifted_take(tmp_path / "shifted"))
    aligned = read_keypoint_frames(demo_take(tmp_path / "aligned", {c: range(15) for c in CAMERAS}))
    # camera 2's frame 5 is its file 5, as in the unshifted set (its sorted order put file 5 at frame 0)
    assert np.array_equal(shifted.people[1][5], read_openpose_file(demo_file("02", 5)))
    assert shifted.numbers == aligned.numbers == list(range(15))
    for c, camera in enumerate(CAMERAS):
        for n in range(15):
            has = n >= 5 if camera == "02" else n < 10
            expected = aligned.people[c][n] if has else np.empty((0, 25, 3))
            assert np.array_equal(shifted.people[c][n], expected), (camera, n)
    assert shifted.absent == [[10, 11, 12, 13, 14], [0, 1, 2, 3, 4], [10, 11, 12, 13, 14], [10, 11, 12, 13, 14]]


def test_each_camera_missing_another_frame_keeps_the_others_in_step(tmp_path: Path) -> None:
    take = demo_take(tmp_path / "take", {c: [n for n in range(8) if n != 2 + i] for i, c in enumerate(CAMERAS)})
    frames = read_keypoint_frames(take)
    for c, camera in enumerate(CAMERAS):
        for n in range(8):
            expected = read_openpose_file(demo_file(camera, n)) if n != 2 + c else np.empty((0, 25, 3))
            assert np.array_equal(frames.people[c][n], expected), (camera, n)
    assert frames.numbers == list(range(8))


def test_the_shifted_take_is_fitted_on_every_number_and_says_which_files_are_missing(tmp_path: Path) -> None:
    result = run_inline(shifted_take(tmp_path / "take"), "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", *QUICK)
    assert result.returncode == 0, result.stderr
    assert "cam02_json has no file for 5 (0, 1, 2, 3, 4)" in result.stderr
    assert "cam01_json has no file for 5 (10, 11, 12, 13, 14)" in result.stderr
    assert [number for number, _ in trc_rows(tmp_path / "p.trc")] == [str(n + 1) for n in range(15)]


def test_frame_numbers_and_times_are_the_inputs_with_a_frame_no_camera_has_as_an_empty_row(tmp_path: Path) -> None:
    take = demo_take(tmp_path / "take", {c: [3, 4, 6, 7] for c in CAMERAS})
    result = run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", *QUICK, "--rate", "50")
    assert result.returncode == 0, result.stderr
    assert "no camera has a file for 1 frame between 3 and 7 (5): written as rows of empty cells" in result.stderr
    assert trc_rows(tmp_path / "p.trc") == [(str(n + 1), repr(n / 50)) for n in range(3, 8)]
    trc = read_trc(tmp_path / "p.trc")  # markerflow reads it back: its rows are evenly spaced
    assert trc.rate == 50.0
    assert np.isnan(trc.positions[2]).all() and np.isfinite(trc.positions[[0, 1, 3, 4]]).all()


def test_a_take_of_every_other_frame_keeps_its_numbers_at_half_the_rate(tmp_path: Path) -> None:
    take = demo_take(tmp_path / "take", {c: [0, 2, 4, 6] for c in CAMERAS})
    result = run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", *QUICK)
    assert result.returncode == 0 and "empty" not in result.stderr, result.stderr
    assert trc_rows(tmp_path / "p.trc") == [(str(n + 1), repr(n / 60)) for n in (0, 2, 4, 6)]
    assert read_trc(tmp_path / "p.trc").rate == 30.0


def refused(tmp_path: Path, take: Path, *words: str) -> None:
    one_line_error(run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", *QUICK), *words)
    assert not (tmp_path / "p.trc").exists()


def test_a_file_without_a_frame_number_is_refused_naming_it(tmp_path: Path) -> None:
    take = demo_take(tmp_path / "take", {c: range(4) for c in CAMERAS})
    (take / "cam03_json" / "cam03.0002.json").rename(take / "cam03_json" / "keypoints.json")
    refused(tmp_path, take, "cam03_json/keypoints.json: no frame number in the file name")


def test_two_files_of_one_frame_number_are_refused_naming_both(tmp_path: Path) -> None:
    take = demo_take(tmp_path / "take", {c: range(4) for c in CAMERAS})
    (take / "cam02_json" / "cam02.0003.json").rename(take / "cam02_json" / openpose_name("02", 2))
    refused(tmp_path, take, "cam02_json: cam02.0002.json and cam02_000000000002_keypoints.json are both frame 2")


def test_a_stray_far_numbered_file_is_refused_not_written_as_empty_rows(tmp_path: Path) -> None:
    take = demo_take(tmp_path / "take", {c: range(4) for c in CAMERAS})
    (take / "cam01_json" / "cam01.0003.json").rename(take / "cam01_json" / "cam01.99999.json")
    refused(tmp_path, take, "no camera has a file between frames 3 and 99999")


def test_image_folders_keep_the_numbers_in_their_names(tmp_path: Path) -> None:
    """Image input was written from row 0 whatever its files were numbered (f0005.png -> Frame# 1)."""
    import cv2
    from pose_scenes import background, walking

    from formulations.pose.human import human_model
    from formulations.pose.render import render_silhouette
    from service.io.calibration import load_calibration

    model, rng = human_model(), np.random.default_rng(0)
    X = walking(model, 3)
    for c, camera in enumerate(load_calibration(CALIBRATION)):
        folder = tmp_path / "take" / f"cam{c + 1:02d}"
        folder.mkdir(parents=True)
        back = background(camera, rng)
        cv2.imwrite(str(folder / "background.png"), back)
        for number, pose in zip((5, 6, 8), X, strict=True):
            cv2.imwrite(str(folder / f"f{number:04d}.png"), render_silhouette(model, pose, camera, back).astype(np.uint8))
    result = run_inline(tmp_path / "take", "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", *QUICK, "--rate", "50")
    assert result.returncode == 0, result.stderr
    assert "no camera has a file for 1 frame between 5 and 8 (7)" in result.stderr
    assert trc_rows(tmp_path / "p.trc") == [(str(n + 1), repr(n / 50)) for n in range(5, 9)]
