"""People from OpenPose keypoints as boxes: boxing, tracking, naming, on the real Pose2Sim demo."""

import json

import numpy as np
import pytest
from conftest import DATA

from service.errors import InputError
from service.io.calibration import load_pose2sim_toml
from service.io.formats.trc import read_trc
from service.people.keypoint_boxes import keypoint_box
from service.people.openpose import read_openpose_folder
from service.people.views import people_views, pose2sim_world

DEMO = DATA / "multicam2d_pose2sim_demo"
TRIAL = DEMO / "multiperson_trial_2persons"
needs_data = pytest.mark.skipif(not TRIAL.exists(), reason="shared data absent")


def test_a_keypoint_box_spans_the_detected_keypoints_padded_by_a_tenth_of_its_height():
    keypoints = np.array([[10, 20, 0.9], [30, 120, 0.8], [500, 500, 0.0], [20, 60, 0.5]])
    np.testing.assert_allclose(keypoint_box(keypoints), [0, 10, 40, 120])
    assert keypoint_box(keypoints[[0, 2]]) is None


def test_a_folder_that_is_not_openpose_is_one_line(tmp_path):
    (tmp_path / "f.0000.json").write_text(json.dumps({"people": [{"pose_keypoints_2d": [1, 2]}]}))
    with pytest.raises(InputError, match="not .x, y, confidence. triples"):
        read_openpose_folder(tmp_path)
    with pytest.raises(InputError, match="no such folder"):
        read_openpose_folder(tmp_path / "missing")


def test_a_keypoint_that_is_not_a_pixel_is_refused_and_a_hand_only_person_left_out(tmp_path):
    """A NaN keypoint was read as a person's point (pose refused it, people did not)."""
    values = [10.0, 20.0, 0.9] * 3
    people = [{"pose_keypoints_2d": values}, {"pose_keypoints_2d": [], "hand_left_keypoints_2d": [1, 2, 3]}]
    (tmp_path / "f.0000.json").write_text(json.dumps({"people": people}))
    numbers, frames = read_openpose_folder(tmp_path)
    assert numbers == [0] and [p.shape for p in frames[0]] == [(3, 3)]
    values[4] = float("nan")
    (tmp_path / "f.0000.json").write_text(json.dumps({"people": [{"pose_keypoints_2d": values}]}))
    with pytest.raises(InputError, match="person 0's keypoint 1 is .*must be finite pixels"):
        read_openpose_folder(tmp_path)


@needs_data
def test_both_participants_are_found_in_nearly_every_camera_frame_and_never_share_a_box():
    cameras = load_pose2sim_toml(DEMO / "calibration" / "Calib_qualisys.toml", units="mm")
    people = {p: pose2sim_world(read_trc(TRIAL / "pose2sim_output_3d" / f"Participants1-2_{p}_0-100.trc").positions)
              for p in ("P1", "P2")}
    views = people_views(sorted((TRIAL / "pose_openpose_body25b").glob("cam*_json")), cameras, people)
    assert views.boxes.shape == (100, 2, 4, 4)
    present = np.isfinite(views.boxes).all(axis=3)
    assert present.mean() >= 0.95
    shared = present.all(axis=1) & np.isclose(views.boxes[:, 0], views.boxes[:, 1]).all(axis=2)
    assert not shared.any()
    # the DP on these views never switches more than the per-frame best
    quality = views.quality()
    dp, greedy = views.choose(1.0, 30), np.argmax(quality, axis=2)
    assert np.count_nonzero(np.diff(dp, axis=0)) <= np.count_nonzero(np.diff(greedy, axis=0))


def test_frames_follow_the_numbers_in_the_file_names_not_their_sorted_order(tmp_path):
    """Sorted names put cam.10.json before cam.9.json: frames out of order without a word."""
    for number in (8, 9, 10):
        (tmp_path / f"cam.{number}.json").write_text(
            json.dumps({"people": [{"pose_keypoints_2d": [float(number), 0.0, 1.0]}]}))
    numbers, frames = read_openpose_folder(tmp_path)
    assert numbers == [8, 9, 10] and [f[0][0, 0] for f in frames] == [8.0, 9.0, 10.0]


@needs_data
def test_cameras_whose_files_are_numbered_differently_are_refused(tmp_path):
    """Paired by position, a camera starting five frames later was boxed out of step."""
    cameras = load_pose2sim_toml(DEMO / "calibration" / "Calib_qualisys.toml", units="mm")
    folders = sorted((TRIAL / "pose_openpose_body25b").glob("cam*_json"))
    copies = []
    for k, folder in enumerate(folders):
        copy = tmp_path / folder.name
        copy.mkdir()
        for path in sorted(folder.glob("*.json"))[5 * (k == 1):][:10]:
            (copy / path.name).write_bytes(path.read_bytes())
        copies.append(copy)
    people = {"P1": np.zeros((10, 3, 3))}
    with pytest.raises(InputError, match=r"the cameras' OpenPose files are numbered differently \(cam01_json 0-9"):
        people_views(copies, cameras, people)
