"""Keypoints and silhouettes through the real Pose2Sim calibration; OpenPose files; the participant."""

from __future__ import annotations

import json

import numpy as np
import pytest
from pose_scenes import background, keypoints, set_angle, silhouette_maps, walking

from formulations.cameras.rig import Rig
from formulations.pose.apf import AnnealingSchedule
from formulations.pose.human import human_model
from formulations.pose.keypoints import BODY_25B
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.silhouette import SilhouetteMeasurement
from service.errors import InputError
from service.io.calibration import load_calibration
from service.pose.openpose import read_openpose_file, write_openpose_file
from service.pose.participant import choose_participant
from service.pose.run import fit_keypoints

CALIBRATION = pytest.importorskip("conftest").DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"
needs_data = pytest.mark.skipif(not CALIBRATION.exists(), reason="Pose2Sim demo calibration not present")


@needs_data
def test_keypoints_rendered_from_a_known_motion_are_fitted_within_35_mm() -> None:
    cameras = load_calibration(CALIBRATION)
    model = human_model()
    X = walking(model, 6)
    detections = keypoints(model, X, cameras, noise_px=1.0, rng=np.random.default_rng(0))
    fit = fit_keypoints(cameras, detections, 1.0, model, AnnealingSchedule(300, 10), seed=0)
    truth = forward_kinematics(model, X).positions
    error = np.linalg.norm(fit.positions - truth, axis=2)
    assert error.mean() < 0.035, error.mean(axis=1)  # the bench measures about 25-30 mm
    assert (fit.positions[:, model.index("RKnee")] != truth[:, model.index("RKnee")]).any()  # not handed the truth


@needs_data
def test_the_silhouette_weight_peaks_at_the_true_knee_angle_as_the_papers_fig_3() -> None:
    cameras = load_calibration(CALIBRATION)
    model = human_model()
    X = walking(model, 1)
    rng = np.random.default_rng(1)
    edges, foreground = silhouette_maps(model, X[0], cameras, [background(c, rng) for c in cameras], rng)
    measurement = SilhouetteMeasurement(Rig.of(cameras), model, edges, foreground)
    true_knee = X[0, model.columns[model.index("RKnee")]]
    angles = np.linspace(0.0, 1.6, 33)
    trial = np.repeat(X, len(angles), axis=0)
    set_angle(model, trial, "RKnee", "y", angles)
    energy = measurement.energy(forward_kinematics(model, trial))
    assert abs(angles[np.argmin(energy)] - true_knee) <= 0.1
    assert energy.max() - energy.min() > 0.05  # a peak, not a plateau


def test_openpose_files_round_trip(tmp_path) -> None:
    people = np.random.default_rng(2).uniform(0, 1000, (2, len(BODY_25B), 3)).round(3)
    write_openpose_file(tmp_path / "cam01.0000.json", people)
    assert np.allclose(read_openpose_file(tmp_path / "cam01.0000.json"), people)
    write_openpose_file(tmp_path / "empty.json", np.empty((0, len(BODY_25B), 3)))
    assert read_openpose_file(tmp_path / "empty.json").shape == (0, len(BODY_25B), 3)


@pytest.mark.parametrize("value", [None, "NaN", "Infinity", 1e30])
def test_a_keypoint_that_is_not_a_pixel_is_refused_in_one_line(tmp_path, value) -> None:
    """A null or NaN keypoint used to reach the particle filter as a non-finite energy."""
    values = [0.0] * (3 * len(BODY_25B))
    values[3 * 5] = value  # LShoulder's x
    text = json.dumps({"people": [{"pose_keypoints_2d": values}]}).replace('"NaN"', "NaN").replace('"Infinity"', "Infinity")
    (tmp_path / "cam01.0000.json").write_text(text)
    with pytest.raises(InputError, match=f"person 0's {BODY_25B[5]} keypoint is .*an undetected keypoint is 0, 0, 0"):
        read_openpose_file(tmp_path / "cam01.0000.json")


@needs_data
def test_the_participant_is_the_person_the_cameras_agree_on_not_a_bystander() -> None:
    cameras = load_calibration(CALIBRATION)
    model = human_model()
    X = walking(model, 5)
    rng = np.random.default_rng(3)
    participant = keypoints(model, X, cameras, 1.0, rng)
    bystander = participant[:, 0].copy()
    bystander[..., 0] -= 300.0  # another body, in camera 0 only, listed first
    people = [[np.stack([bystander[f], participant[f, 0]]) if c == 0 else participant[f, c][None] for f in range(5)]
              for c in range(len(cameras))]
    people[1][2] = np.empty((0, len(BODY_25B), 3))  # camera 1 loses everyone for a frame
    chosen = choose_participant(Rig.of(cameras), people)
    assert np.allclose(chosen[:, 0], participant[:, 0])
    assert (chosen[2, 1] == 0).all() and np.allclose(chosen[3, 1], participant[3, 1])
