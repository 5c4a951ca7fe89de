"""The bounded refinement after the APF, and the subject's proportions calibrated from keypoints."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pytest
from pose_scenes import keypoints, set_angle, walking

from formulations.cameras.rig import Rig
from formulations.pose.human import Proportions, human_model
from formulations.pose.initial import fit_proportions
from formulations.pose.keypoints import BODY_25B, KeypointMeasurement, KeypointPairs
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.refine import refine
from service.io.calibration import load_calibration

CALIBRATION = pytest.importorskip("conftest").DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"
needs_data = pytest.mark.skipif(not CALIBRATION.exists(), reason="Pose2Sim demo calibration not present")
ODD = Proportions(thigh=0.45, shank=0.39, foot=0.17, heel_back=0.04, ankle_height=0.06, trunk=0.55,
                  shoulder_drop=0.07, shoulder_half_width=0.17, upper_arm=0.31, forearm=0.24,
                  neck_to_head_top=0.27, nose_forward=0.11, nose_up=0.15)


def _measurement(model, X, noise_px: float, seed: int = 0) -> KeypointMeasurement:
    cameras = load_calibration(CALIBRATION)
    detections = keypoints(model, X[None], cameras, noise_px, np.random.default_rng(seed))[0]
    return KeypointMeasurement(Rig.of(cameras), KeypointPairs.of(model), detections, sigma=5.0)


@needs_data
def test_refinement_recovers_a_pose_from_a_perturbed_start() -> None:
    model = human_model()
    truth = walking(model, 1)[0]
    measurement = _measurement(model, truth, noise_px=0.5)
    rng = np.random.default_rng(1)
    start = model.clip((truth + np.r_[0.03, -0.02, 0.02, rng.normal(0, 0.08, model.dof - 3)])[None])[0]
    refined = refine(model, measurement, start, iterations=100)
    joints = forward_kinematics(model, np.stack([start, refined, truth])).positions
    before, after = (np.linalg.norm(joints[i] - joints[2], axis=1).mean() for i in (0, 1))
    assert after < 0.01 < before, (before, after)  # from centimetres off to under a centimetre


@needs_data
def test_refinement_stays_inside_the_joint_limits_and_keeps_the_bones() -> None:
    model = human_model()
    beyond = walking(model, 1)[0]
    set_angle(model, beyond[None], "RKnee", "y", np.array([-0.4]))  # hyperextended: the knee's limit is 0
    set_angle(model, beyond[None], "LElbow", "y", np.array([0.5]))  # bent backwards: the elbow's limit is 0
    measurement = _measurement(model, beyond, noise_px=0.0)
    refined = refine(model, measurement, model.clip(beyond[None])[0])
    assert (refined >= model.lower).all() and (refined <= model.upper).all()
    for joint in ("RKnee", "LElbow"):
        assert refined[model.columns[model.index(joint)]] == pytest.approx(0.0, abs=1e-3)  # pressed on the limit
    joints = forward_kinematics(model, refined[None]).positions[0]
    thigh = np.linalg.norm(joints[model.index("RHip")] - joints[model.index("RKnee")])
    assert thigh == pytest.approx(Proportions().thigh, abs=1e-9)


def test_proportions_are_recovered_from_the_keypoints_of_a_body_in_motion() -> None:
    model = human_model(ODD)
    X = walking(model, 40)
    positions = forward_kinematics(model, X).positions
    points = {name: positions[:, model.index(name)] for name in model.names if name in BODY_25B}
    fitted = asdict(fit_proportions(points, 1.0))
    for name, value in asdict(ODD).items():
        # The big toe sits 1 cm to the side of the heel's line, which the foot's triangle ignores.
        assert fitted[name] == pytest.approx(value, abs=2e-3 if name in ("foot", "heel_back", "ankle_height") else 1e-6), name
