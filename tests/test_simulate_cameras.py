"""Camera-mode simulator on CMU/HDM05 85_02 placed in the Pose2Sim Qualisys rig."""

import ezc3d
import numpy as np
import pytest
from conftest import DATA

from formulations.cameras.rig import Rig
from service.errors import InputError
from service.evaluation.simulate_cameras import place_in_volume, simulate_cameras
from service.io.calibration import load_pose2sim_toml
from service.io.recording import Recording

CALIBRATION = DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"
CMU_85_02 = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
CLEAN = {
    "pixel_noise": 0.0,
    "merge_radius_px": 0.0,
    "occlusion_rate": 0.0,
    "occlusion_burst_frames": 1.0,
    "clutter_per_camera": 0.0,
    "seed": 0,
}


@pytest.fixture(scope="module")
def rig() -> Rig:
    return rig_from(CALIBRATION)


@pytest.fixture(scope="module")
def placed(rig: Rig) -> Recording:
    c3d = ezc3d.c3d(str(CMU_85_02))
    positions = c3d["data"]["points"][:3].transpose(2, 1, 0)
    names = c3d["parameters"]["POINT"]["LABELS"]["value"]
    return Recording(names, place_in_volume(positions, rig), 120.0)


@pytest.fixture(scope="module")
def clean(placed: Recording, rig: Rig):
    return simulate_cameras(placed, rig, **CLEAN)


def _projections(rig: Rig, positions: np.ndarray) -> np.ndarray:
    """(frames, cameras, markers, 2) projection of every sample by each camera on its own."""
    F, N = positions.shape[:2]
    per_camera = [camera.project(positions.reshape(-1, 3)).reshape(F, N, 2) for camera in rig.cameras]
    return np.stack(per_camera, axis=1)


def _seen(capture) -> np.ndarray:
    return capture.marker_detection >= 0


def test_rig_reads_pose2sim_toml_in_millimetres(rig: Rig):
    assert len(rig) == 4 and all(camera.distortion.shape == (4,) for camera in rig.cameras)
    assert rig.image_size.tolist() == [[1088.0, 1920.0]] * 4
    assert rig.extrinsic[0, :, 3] == pytest.approx([321.10489, 956.33206, 2890.71305])


def test_placed_markers_are_seen_by_at_least_two_cameras(clean):
    seen = _seen(clean)
    assert (seen.sum(axis=1) >= 2).mean() >= 0.90
    assert (seen.mean(axis=(0, 2)) >= 0.80).all()


def test_clean_detections_are_the_projections_of_their_markers(clean, placed, rig):
    expected = _projections(rig, placed.positions)
    for f, per_camera in enumerate(clean.detections):
        for c, xy in enumerate(per_camera):
            markers = clean.detection_markers[f][c]
            assert (markers >= 0).all()
            np.testing.assert_allclose(xy, expected[f, c, markers], atol=1e-6, rtol=0)
            seen = np.flatnonzero(clean.marker_detection[f, c] >= 0)
            assert sorted(markers) == seen.tolist()
            assert (
                clean.marker_detection[f, c, markers] == np.arange(len(markers))
            ).all()
    np.testing.assert_array_equal(clean.first_frame.positions, placed.positions[:1])


def test_occlusion_rate_and_burst_length_match_the_settings(clean, placed, rig):
    settings = dict(CLEAN, occlusion_rate=0.2, occlusion_burst_frames=8.0, seed=3)
    capture = simulate_cameras(placed, rig, **settings)
    in_view = _seen(clean)
    occluded = in_view & ~_seen(capture)
    assert not occluded[0].any()
    assert occluded[1:].sum() / in_view[1:].sum() == pytest.approx(0.2, rel=0.15)
    starts = occluded[1:] & ~occluded[:-1]
    assert occluded.sum() / starts.sum() == pytest.approx(8.0, rel=0.15)


def test_clutter_count_and_pixel_noise_match_the_settings(placed, rig):
    settings = dict(CLEAN, pixel_noise=0.5, clutter_per_camera=3.0, seed=5)
    capture = simulate_cameras(placed, rig, **settings)
    expected = _projections(rig, placed.positions)
    clutter, residuals = [], []
    for f, per_camera in enumerate(capture.detections):
        for c, xy in enumerate(per_camera):
            markers = capture.detection_markers[f][c]
            clutter.append((markers < 0).sum())
            assert ((xy >= -0.5) & (xy <= rig.image_size[c] - 0.5)).all()  # on the sensor, as Camera.in_image
            residuals.append(xy[markers >= 0] - expected[f, c, markers[markers >= 0]])
    assert np.mean(clutter) == pytest.approx(3.0, rel=0.05)
    assert np.concatenate(residuals).std() == pytest.approx(0.5, rel=0.05)


def test_projections_two_pixels_apart_merge_at_their_mean(rig: Rig):
    centre = place_in_volume(np.zeros((1, 1, 3)), rig)[0, 0]
    camera = rig.cameras[0]
    depth = camera.R[2] @ centre + camera.t[2]
    # Two pixels along camera 0's image x at that depth; a third marker 300 mm away.
    positions = np.stack(
        [centre, centre + camera.R[0] * 2.0 * depth / camera.K[0, 0], centre]
    )
    positions[2, 2] += 300.0
    truth = Recording(["a", "b", "far"], np.repeat(positions[None], 2, axis=0), 120.0)
    capture = simulate_cameras(truth, rig, **dict(CLEAN, merge_radius_px=3.0))
    expected = _projections(rig, truth.positions)
    assert np.linalg.norm(expected[0, 0, 0] - expected[0, 0, 1]) == pytest.approx(
        2.0, abs=0.05
    )
    for c in range(len(rig)):
        detection = capture.marker_detection[0, c]
        if np.linalg.norm(expected[0, c, 0] - expected[0, c, 1]) < 3.0:
            assert detection[0] == detection[1] != detection[2]
            merged = capture.detections[0][c][detection[0]]
            np.testing.assert_allclose(
                merged, expected[0, c, :2].mean(axis=0), atol=1e-6
            )
            assert capture.detection_markers[0][c].tolist().count(0) == 1
            assert len(capture.detections[0][c]) == 2
    assert capture.marker_detection[0, 0, 0] == capture.marker_detection[0, 0, 1]


def test_same_seed_same_capture_and_different_seeds_differ(placed, rig):
    short = Recording(placed.names, placed.positions[:100], placed.rate)
    settings = {
        "pixel_noise": 0.5,
        "merge_radius_px": 4.0,
        "occlusion_rate": 0.1,
        "occlusion_burst_frames": 5.0,
        "clutter_per_camera": 2.0,
    }
    a, b, other = (simulate_cameras(short, rig, **settings, seed=s) for s in (7, 7, 8))
    np.testing.assert_array_equal(a.marker_detection, b.marker_detection)
    for f in range(short.n_frames):
        for c in range(len(rig)):
            np.testing.assert_array_equal(a.detections[f][c], b.detections[f][c])
            np.testing.assert_array_equal(
                a.detection_markers[f][c], b.detection_markers[f][c]
            )
    assert not np.array_equal(a.marker_detection, other.marker_detection)


def test_bad_settings_and_unlabeled_first_frame_are_input_errors(placed, rig):
    with pytest.raises(InputError, match="occlusion rate"):
        simulate_cameras(
            placed, rig, **dict(CLEAN, occlusion_rate=0.9, occlusion_burst_frames=2)
        )
    gappy = placed.positions[:3].copy()
    gappy[0, 4] = np.nan
    with pytest.raises(InputError, match=placed.names[4]):
        simulate_cameras(Recording(placed.names, gappy, 120.0), rig, **CLEAN)


def rig_from(path) -> Rig:
    return Rig.of(load_pose2sim_toml(path, units="mm"))
