"""Markers as the measurement: a body built from a subject model fitted to unlabeled points or camera
detections, filling a marker no camera saw."""

from __future__ import annotations

import numpy as np

from formulations.cameras.camera import Camera
from formulations.cameras.rig import Rig
from formulations.pose.apf import AnnealingSchedule
from formulations.pose.from_subject import subject_body
from formulations.pose.kinematics import forward_kinematics, marker_positions
from formulations.pose.markers import MarkerCloudMeasurement, MarkerDetectionMeasurement
from formulations.pose.tracker import PoseTracker, dispersion
from formulations.subject.model import Joint, Limb, Segment, SubjectModel


def leg() -> SubjectModel:
    """Pelvis, thigh and shank, three markers each, mm."""
    pelvis = Segment("PEL", ["P1", "P2", "P3"], [[0, 0, 0], [120, 0, 0], [60, 80, 30]], [1, 1, 1])
    thigh = Segment("THI", ["T1", "T2", "T3"], [[60, 0, -150], [60, 60, -200], [0, 40, -300]], [1, 1, 1])
    shank = Segment("SHA", ["S1", "S2", "S3"], [[60, 0, -550], [60, 60, -600], [0, 40, -700]], [1, 1, 1])
    return SubjectModel(
        [pelvis, thigh, shank],
        [Joint("HIP", ("PEL", "THI"), ([60, 40, -60], [60, 40, -60]), 1.0),
         Joint("KNE", ("THI", "SHA"), ([60, 40, -460], [60, 40, -460]), 1.0)],
        [Limb("THI", ("HIP", "KNE"), 400.0)], [],
    )


def _pose(body, rng) -> np.ndarray:
    X = np.zeros(body.dof)
    X[:3] = (200.0, -100.0, 900.0)
    X[3:] = rng.uniform(-0.4, 0.4, body.dof - 3)
    return X


def _fit(body, truth: np.ndarray, measurement, rng) -> np.ndarray:
    start = truth + np.r_[rng.normal(0, 20, 3), rng.normal(0, 0.15, body.dof - 3)]
    tracker = PoseTracker(body, start, dispersion(body, 30.0, 0.2), AnnealingSchedule(300, 20), seed=0)
    return tracker.step([measurement])[0]


def test_a_marker_lost_by_every_camera_is_filled_from_unlabeled_points() -> None:
    body = subject_body(leg())
    assert len(body.cones) == 1 and len(body.markers) == 9
    rng = np.random.default_rng(0)
    truth = _pose(body, rng)
    markers = marker_positions(body, forward_kinematics(body, truth[None]))[0]
    seen = np.delete(markers, 7, axis=0) + rng.normal(0, 1.0, (8, 3))  # S2 lost, 1 mm noise
    points = rng.permutation(np.vstack([seen, [[900.0, 900.0, 900.0]]]))  # and a ghost
    estimate = _fit(body, truth, MarkerCloudMeasurement(body, points, sigma=10.0), rng)
    filled = marker_positions(body, forward_kinematics(body, estimate[None]))[0]
    assert np.linalg.norm(filled[7] - markers[7]) < 30.0  # the start is 60-100 mm off
    assert np.linalg.norm(filled - markers, axis=1).mean() < 15.0


def test_markers_are_fitted_from_2d_detections() -> None:
    body = subject_body(leg())
    rng = np.random.default_rng(1)
    truth = _pose(body, rng)
    markers = marker_positions(body, forward_kinematics(body, truth[None]))[0]
    target = markers.mean(axis=0)
    cameras = []
    for angle in (0.0, 1.6, 3.2):
        centre = target + 3000.0 * np.array([np.cos(angle), np.sin(angle), 0.3])
        z = (target - centre) / np.linalg.norm(target - centre)
        x = np.cross(z, [0.0, 0.0, 1.0])
        x /= np.linalg.norm(x)
        R = np.vstack([x, np.cross(z, x), z])
        K = [[1500, 0, 640], [0, 1500, 512], [0, 0, 1]]
        cameras.append(Camera(K, np.zeros(4), R, -R @ centre, (1280, 1024), f"c{angle}"))
    detections = tuple(rng.permutation(camera.project(markers) + rng.normal(0, 0.5, (9, 2))) for camera in cameras)
    estimate = _fit(body, truth, MarkerDetectionMeasurement(Rig.of(cameras), body, detections), rng)
    filled = marker_positions(body, forward_kinematics(body, estimate[None]))[0]
    assert np.linalg.norm(filled - markers, axis=1).mean() < 15.0
