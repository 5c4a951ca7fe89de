"""Scenario keys past their documented bounds, and evaluations too short to score, are refused in one line."""

from pathlib import Path

import numpy as np
import pytest

from service.errors import InputError
from service.evaluation.cameras import evaluate_cameras
from service.evaluation.cloud import evaluate
from service.evaluation.scenario import Scenario
from service.evaluation.simulate_cameras import place_in_volume, simulate_cameras
from service.evaluation.simulate_cloud import simulate_cloud
from service.io.recording import Recording


def _walk(frames: int = 6, markers: int = 4) -> Recording:
    """A few markers moving slowly: any scenario simulates on it in milliseconds."""
    rng = np.random.default_rng(0)
    base = rng.uniform(-300.0, 300.0, (1, markers, 3))
    steps = np.arange(frames)[:, None, None] * np.array([2.0, 0.0, 0.0])
    return Recording([f"m{i}" for i in range(markers)], base + steps, 100.0)


@pytest.mark.parametrize(("key", "value"), [
    ("ghosts_per_frame", 1e6), ("ghosts_per_frame", 1e30), ("noise_mm", 1e300), ("ghost_spread_mm", 1e300),
])
def test_huge_cloud_keys_are_refused_naming_key_and_bound(key, value):
    with pytest.raises(InputError, match=rf"'{key}' must be .*<= ") as error:
        Scenario.from_dict({key: value})
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("key", ["clutter_per_camera", "pixel_noise", "merge_radius_px"])
def test_huge_camera_keys_are_refused(key):
    with pytest.raises(InputError, match=rf"'{key}' must be .*<= "):
        Scenario.from_dict({"mode": "cameras", "calibration": "rig.toml", key: 1e30})


def test_bounds_are_inclusive_and_generous():
    scenario = Scenario.from_dict({"ghosts_per_frame": 1000, "noise_mm": 1000, "ghost_spread_mm": 10000})
    assert scenario.ghosts_per_frame == 1000.0


@pytest.mark.parametrize(("start", "frames"), [(0, 1), (5, 0), (5, 1)])
def test_one_frame_slice_is_refused(start, frames):
    scenario = Scenario.from_dict({"start_frame": start, "frames": frames})
    with pytest.raises(InputError, match="needs at least 2 frames"):
        simulate_cloud(_walk(), scenario)
    with pytest.raises(InputError, match="needs at least 2 frames"):
        evaluate(_walk(), scenario)


def test_two_frames_still_simulate():
    capture = simulate_cloud(_walk(), Scenario.from_dict({"start_frame": 4}))
    assert len(capture.cloud.points) == 2


def test_camera_simulation_refuses_one_frame():
    with pytest.raises(InputError, match="needs at least 2 frames"):
        simulate_cameras(_walk(1), None, 0.5, 3.0, 0.1, 15.0, 2.0, 0)  # type: ignore[arg-type]


def test_placing_no_frames_is_refused_without_warning():
    with pytest.raises(InputError, match="needs at least 2 frames"):
        place_in_volume(np.zeros((0, 3, 3)), None)  # type: ignore[arg-type]


@pytest.mark.parametrize(("start", "frames", "match"), [
    (7, 0, "'start_frame' 7 is past the end"), (4, 5, "start_frame \\+ frames = 9 exceeds"), (5, 0, "at least 2 frames"),
])
def test_camera_scenarios_name_the_span_key_as_cloud_ones_do(start, frames, match):
    calibration = Path(__file__).resolve().parents[2] / "shared/data/multicam2d_pose2sim_demo/calibration/Calib_qualisys.toml"
    scenario = Scenario.from_dict({"mode": "cameras", "calibration": str(calibration), "start_frame": start, "frames": frames})
    with pytest.raises(InputError, match=match):
        evaluate_cameras(_walk(), scenario)
