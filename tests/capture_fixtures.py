"""Small captures in both input modes, from real motion, for document and resume tests."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from conftest import DATA

from formulations.cameras.camera import Camera
from formulations.cameras.rig import Rig
from service.capture.capture import Capture
from service.capture.from_recording import capture_from_recording
from service.evaluation.simulate_cameras import CameraCapture, place_in_volume, simulate_cameras
from service.io.calibration import load_pose2sim_toml
from service.io.formats import read_labeled
from service.io.recording import Recording

CMU = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
POSE2SIM = DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"


def points_capture(frames: int) -> Capture:
    truth = read_labeled(CMU)
    return capture_from_recording(Recording(truth.names, truth.positions[:frames], truth.rate), shuffle=True)


def simulated_cmu(frames: int, markers: int = 41, seed: int = 0) -> tuple[list[Camera], CameraCapture]:
    """CMU 85_02 through the real Pose2Sim rig with the issue's scenario (0.5 px noise, 3 px
    merging, 10 % occlusion in 15-frame bursts, 2 clutter points per camera)."""
    cameras = load_pose2sim_toml(POSE2SIM, units="mm")
    truth = read_labeled(CMU)
    rig = Rig.of(cameras)
    placed = Recording(truth.names[:markers], place_in_volume(truth.positions[:frames, :markers], rig), truth.rate)
    simulated = simulate_cameras(placed, rig, pixel_noise=0.5, merge_radius_px=3.0, occlusion_rate=0.1,
                                 occlusion_burst_frames=15, clutter_per_camera=2, seed=seed)
    return cameras, simulated


def camera_capture(frames: int, markers: int = 41, seed: int = 0) -> Capture:
    return capture_of(*simulated_cmu(frames, markers, seed))


def capture_of(cameras: list[Camera], simulated: CameraCapture) -> Capture:
    """What a user hands markerflow of a simulated camera capture: detections and frame 0."""
    first = simulated.first_frame
    return Capture(first.names, first.positions[0], first.rate, cameras=cameras, detections=simulated.detections)


def seen_once_in_frame0(cameras: list[Camera], simulated: CameraCapture, marker: int) -> tuple[Capture, np.ndarray]:
    """The capture with ``marker``'s frame-0 detection left out of every camera but the last,
    and ``(N, C)`` each marker's frame-0 detection there (-1 none)."""
    capture = capture_of(cameras, simulated)
    expected = simulated.marker_detection[0].T.copy()
    assert (expected[marker] >= 0).all()  # the simulation shows every marker to every camera in frame 0
    detections = [list(frame) for frame in capture.detections]
    for c in range(len(cameras) - 1):
        detections[0][c] = np.delete(detections[0][c], expected[marker, c], axis=0)
        expected[:, c] -= expected[:, c] > expected[marker, c]
        expected[marker, c] = -1
    return replace(capture, detections=detections), expected
