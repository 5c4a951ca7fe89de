"""Cameras, the rig's triangulation and ray, and calibration loaders, checked by hand and on two real calibrations."""

import csv
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from formulations.cameras.camera import Camera
from formulations.cameras.rig import Rig
from service.errors import InputError
from service.io.calibration import (
    load_calibration,
    load_caliscope_toml,
    load_markerflow_json,
    load_pose2sim_toml,
    save_markerflow_json,
)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
POSE2SIM = DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"
CALISCOPE = DATA / "multicam2d_caliscope_charuco" / "4_cam_recording"
needs_data = pytest.mark.skipif(not POSE2SIM.exists() or not CALISCOPE.exists(), reason="shared data absent")


def simple_camera(**changes) -> Camera:
    fields = {"K": [[800.0, 0, 320], [0, 820.0, 240], [0, 0, 1]], "distortion": np.zeros(5),
              "R": cv2.Rodrigues(np.array([0.1, -0.2, 0.3]))[0], "t": [0.1, -0.2, 2.0], "image_size": (640, 480),
              "name": "simple"}
    return Camera(**{**fields, **changes})


def pose2sim_volume(cameras: list[Camera], rng: np.random.Generator, n: int, unit_per_mm: float = 1.0) -> np.ndarray:
    """n points where the demo subject stands (box from Pose2Sim's own TRC), inside every image."""
    points = unit_per_mm * rng.uniform([-1600, -800, 0], [-300, 600, 1800], size=(2 * n, 3))
    visible = np.all([cam.in_image(cam.project(points)) for cam in cameras], axis=0)
    return points[visible][:n]


def ray(cam: Camera, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Origin (3,) and unit directions (N, 3) of the world rays through pixels."""
    return cam.centre, cam.direction(cam.undistort(pixels))


def triangulated(rig: Rig, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """DLT points (P, 3), reprojection RMS (P,) over the views and views (P,) of (P, C, 2) pixels."""
    points = rig.triangulate(rig.undistort(pixels))
    errors = rig.errors(points, pixels)
    n_views = np.isfinite(pixels).all(axis=2).sum(axis=1)
    return points, np.sqrt(np.nansum(errors**2, axis=1) / np.maximum(n_views, 1)), n_views


def test_project_matches_hand_computation():
    cam = simple_camera()
    points = np.array([[0.0, 0.0, 0.0], [0.3, -0.1, 0.5], [-0.2, 0.4, -0.3]])
    camera_coords = points @ cam.R.T + cam.t
    expected = (camera_coords @ cam.K.T)[:, :2] / camera_coords[:, 2:]
    np.testing.assert_allclose(cam.project(points), expected, atol=1e-9)
    np.testing.assert_allclose(cam.R @ cam.centre + cam.t, 0.0, atol=1e-12)


@needs_data
@pytest.mark.parametrize("path", [POSE2SIM, CALISCOPE / "camera_array.toml"])
def test_projected_point_lies_on_its_ray(path):
    rng = np.random.default_rng(0)
    for cam in load_calibration(path):
        # points 1-3 m in front of the camera, inside the image (where distortion is largest at the edges)
        pixels = rng.uniform([0, 0], cam.image_size, size=(200, 2))
        origins, directions = ray(cam, pixels)
        points = origins + rng.uniform(1.0, 3.0, size=(200, 1)) * directions
        np.testing.assert_allclose(cam.project(points), pixels, atol=1e-6)
        origins, directions = ray(cam, cam.project(points))
        offset = points - origins
        off_ray = offset - np.einsum("nd,nd->n", offset, directions)[:, None] * directions
        assert np.abs(off_ray).max() < 1e-6
        assert (np.einsum("nd,nd->n", offset, directions) > 0).all()
        np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)


def test_in_image_and_scaled():
    cam = simple_camera()
    mask = cam.in_image([[0, 0], [639.4, 479.4], [-0.6, 10], [10, 480], [np.nan, 5]])
    assert mask.tolist() == [True, True, False, False, False]
    mm = cam.scaled(1000.0)
    points = np.array([[0.3, -0.1, 0.5], [0.0, 0.2, 0.1]])
    np.testing.assert_allclose(mm.project(points * 1000.0), cam.project(points), atol=1e-9)
    np.testing.assert_allclose(mm.centre, cam.centre * 1000.0)
    assert pytest.approx(cam.R) == cam.from_rvec(cam.K, cam.distortion, cam.rvec, cam.t, cam.image_size, cam.name).R


@pytest.mark.parametrize(
    "changes, problem",
    [
        ({"K": [[0.0, 0, 320], [0, 820.0, 240], [0, 0, 1]]}, "K is singular"),
        ({"R": np.diag([1.0, 1.0, -1.0])}, "R is not a rotation"),
        ({"R": 2 * np.eye(3)}, "R is not a rotation"),
        ({"t": [1.0, 2.0]}, "t must be"),
        ({"t": [1.0, np.nan, 2.0]}, "t has non-finite"),
        ({"distortion": [0.1, 0.2, 0.3]}, "distortion has 3"),
        ({"image_size": (640, 0)}, "image_size"),
    ],
)
def test_camera_rejects_bad_parameters(changes, problem):
    with pytest.raises(ValueError, match=f"camera 'simple': {problem}"):
        simple_camera(**changes)


def test_a_rotation_printed_to_5_decimals_is_taken_as_the_rotation_it_rounds():
    """Refused before (|R R^T - I| = 7.7e-6 over a 1e-6 tolerance), as calibration files print it."""
    exact = Camera.from_rvec(np.diag([800.0, 800.0, 1.0]) + [[0, 0, 320], [0, 0, 240], [0, 0, 0]], np.zeros(5),
                             np.array([0.3, -1.2, 0.4]), np.array([10.0, 20.0, 2000.0]), (640, 480), "simple")
    printed = simple_camera(K=exact.K, R=np.round(exact.R, 5), t=exact.t)
    assert np.abs(printed.R @ printed.R.T - np.eye(3)).max() < 1e-12
    points = np.random.default_rng(4).uniform(-300, 300, (20, 3))
    np.testing.assert_allclose(printed.project(points), exact.project(points), atol=0.01)
    with pytest.raises(ValueError, match="R is not a rotation .*; give it to 6 decimals, or as rvec"):
        simple_camera(R=np.round(exact.R, 2))


@needs_data
def test_dlt_recovers_points_through_real_calibration():
    cameras = load_pose2sim_toml(POSE2SIM, units="mm")
    rng = np.random.default_rng(1)
    points = pose2sim_volume(cameras, rng, 500)
    pixels = np.stack([cam.project(points) for cam in cameras], axis=1)
    rig = Rig.of(cameras)
    estimate, rms, n_views = triangulated(rig, pixels)
    assert np.abs(estimate - points).max() < 1e-6  # mm
    assert rms.max() < 1e-6 and (n_views == 4).all()

    noisy = pixels + rng.normal(scale=0.5, size=pixels.shape)
    estimate, rms, _ = triangulated(rig, noisy)
    error = np.linalg.norm(estimate - points, axis=1)
    print(f"0.5 px noise: 3D RMSE {np.sqrt(np.mean(error**2)):.3f} mm, reprojection RMS median {np.median(rms):.3f} px")
    assert np.sqrt(np.mean(error**2)) < 1.5
    assert 0.2 < np.median(rms) < 0.6


@needs_data
def test_dlt_batch_equals_per_point_in_either_unit():
    metres = Rig.of(load_pose2sim_toml(POSE2SIM))
    millimetres = Rig.of(load_pose2sim_toml(POSE2SIM, units="mm"))
    rng = np.random.default_rng(2)
    points = pose2sim_volume(metres.cameras, rng, 60, unit_per_mm=1e-3)
    pixels = metres.project(points) + rng.normal(scale=1.0, size=(60, 4, 2))
    pixels[rng.random((60, 4)) < 0.4] = np.nan
    normalised = metres.undistort(pixels)
    estimate, rms, n_views = triangulated(metres, pixels)
    assert (n_views < 2).any() and (n_views == 2).any()
    # The solve must not depend on the unit (the preconditioning).
    np.testing.assert_allclose(millimetres.triangulate(normalised), 1000.0 * estimate, rtol=0, atol=1e-6)
    errors = metres.errors(estimate, pixels)
    for p in range(len(points)):
        if n_views[p] < 2:
            assert np.isnan(estimate[p]).all()
            continue
        np.testing.assert_allclose(metres.triangulate(normalised[p : p + 1])[0], estimate[p], atol=1e-9)
        seen = ~np.isnan(errors[p])
        assert seen.sum() == n_views[p]
        assert np.sqrt(np.mean(errors[p, seen] ** 2)) == pytest.approx(rms[p])


def test_on_ray_is_the_ray_point_nearest_the_prediction():
    cam = simple_camera()
    rig = Rig.of([cam])
    rng = np.random.default_rng(3)
    pixels = rng.uniform([50, 50], [590, 430], size=(20, 2))
    predictions = cam.centre + rng.normal(scale=0.5, size=(20, 3)) + 2.0 * cam.R[2]  # ~2 m in front
    origin, directions = ray(cam, pixels)
    on_ray = rig.on_ray(0, cam.undistort(pixels), predictions)
    for n in range(20):
        # independent derivation: the least-squares s of o + s d = p
        along = np.linalg.lstsq(directions[n][:, None], predictions[n] - origin, rcond=None)[0]
        np.testing.assert_allclose(on_ray[n], origin + along * directions[n], atol=1e-12)
    np.testing.assert_allclose(cam.project(on_ray), pixels, atol=1e-6)  # on the ray through the pixel
    np.testing.assert_allclose(np.cross(on_ray - origin, directions), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("nd,nd->n", predictions - on_ray, directions), 0.0, atol=1e-12)
    behind = cam.centre - 2.0 * cam.R[2]  # the nearest point of the ray is its origin
    np.testing.assert_allclose(rig.on_ray(0, cam.undistort(pixels[:1]), behind[None]), cam.centre[None], atol=1e-12)


@needs_data
def test_charuco_reprojection_error_real_detections():
    cameras = load_caliscope_toml(CALISCOPE / "camera_array.toml")
    column = {cam.name: c for c, cam in enumerate(cameras)}
    with open(CALISCOPE / "xy.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    corners = sorted({(int(r["sync_index"]), int(r["keypoint_id"])) for r in rows})
    index = {corner: i for i, corner in enumerate(corners)}
    pixels = np.full((len(corners), len(cameras), 2), np.nan)
    for r in rows:
        pixels[index[int(r["sync_index"]), int(r["keypoint_id"])], column[f"cam_{r['cam_id']}"]] = (
            float(r["img_loc_x"]), float(r["img_loc_y"]))
    rig = Rig.of(cameras)
    points, _, n_views = triangulated(rig, pixels)
    seen = n_views >= 2
    errors = rig.errors(points[seen], pixels[seen])
    errors = errors[np.isfinite(errors)]
    median = float(np.median(errors))
    print(f"ChArUco: {seen.sum()} corners, {errors.size} detections, median reprojection {median:.3f} px, "
          f"90th percentile {np.percentile(errors, 90):.2f} px")
    assert seen.sum() > 500 and errors.size == n_views[seen].sum()
    assert median <= 0.6


@needs_data
def test_real_calibrations_load():
    pose2sim = load_calibration(POSE2SIM)
    assert [c.name for c in pose2sim] == ["cam_01", "cam_02", "cam_03", "cam_04"]
    assert all(c.image_size == (1088, 1920) for c in pose2sim)
    caliscope = load_calibration(CALISCOPE / "camera_array.toml")
    assert [c.name for c in caliscope] == ["cam_0", "cam_1", "cam_2", "cam_3"]
    assert all(c.image_size == (1280, 720) and c.distortion.size == 5 for c in caliscope)
    in_mm = load_calibration(POSE2SIM, units="mm")
    np.testing.assert_allclose(in_mm[0].t, pose2sim[0].t * 1000.0)


@needs_data
def test_json_round_trip(tmp_path):
    cameras = load_pose2sim_toml(POSE2SIM, units="mm") + load_caliscope_toml(CALISCOPE / "camera_array.toml", units="mm")
    path = tmp_path / "calibration.json"
    save_markerflow_json(path, cameras, units="mm")
    assert load_calibration(path) == cameras
    np.testing.assert_allclose(load_markerflow_json(path, units="m")[0].t, cameras[0].t / 1000.0)


def json_calibration(tmp_path, **changes) -> Path:
    entry = {"name": "left", "K": [[800, 0, 320], [0, 800, 240], [0, 0, 1]], "distortion": [0, 0, 0, 0],
             "rvec": [0.1, 0.2, 0.3], "t": [0, 0, 2000], "image_size": [640, 480]}
    entry = {k: v for k, v in {**entry, **changes}.items() if v is not None}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"units": "mm", "cameras": [entry]}))
    return path


@pytest.mark.parametrize(
    "changes, problem",
    [
        ({"K": None}, "missing key 'K'"),
        ({"K": [[800, 0, 320], [0, 0, 240], [0, 0, 1]]}, "K is singular"),
        ({"rvec": None, "R": [[1, 0, 0], [0, 1, 0], [0, 0.5, 1]]}, "R is not a rotation"),
        ({"rvec": [1, "x", 2]}, "rvec must be"),
    ],
)
def test_bad_json_names_file_camera_and_problem(tmp_path, changes, problem):
    with pytest.raises(InputError, match=f"bad.json: camera 'left': {problem}") as info:
        load_calibration(json_calibration(tmp_path, **changes))
    assert "\n" not in str(info.value)


@needs_data
def test_bad_toml_names_camera(tmp_path):
    text = POSE2SIM.read_text()
    start = text.index("[cam_02]")
    missing = text[:start] + text[start:].replace("matrix = ", "matrixx = ", 1)
    (tmp_path / "missing.toml").write_text(missing)
    with pytest.raises(InputError, match="missing.toml: camera 'cam_02': missing key 'matrix'"):
        load_calibration(tmp_path / "missing.toml")

    text = (CALISCOPE / "camera_array.toml").read_text()
    start = text.index("[cameras.2]")
    singular = text[:start] + text[start:].replace("matrix = [[637.2292860850233", "matrix = [[0.0", 1)
    (tmp_path / "singular.toml").write_text(singular)
    with pytest.raises(InputError, match="singular.toml: camera 'cam_2': K is singular"):
        load_calibration(tmp_path / "singular.toml")

    (tmp_path / "broken.toml").write_text("[cam_01\nmatrix = 1")
    with pytest.raises(InputError, match="broken.toml: cannot read calibration"):
        load_calibration(tmp_path / "broken.toml")
    with pytest.raises(InputError, match="unknown calibration format"):
        load_calibration(tmp_path / "calib.qca.txt")
