"""Cross-camera matching: synthetic points through the real caliscope cameras, then real ChArUco corners."""

import time
from pathlib import Path

import numpy as np
import pytest

from formulations.cross_camera import (
    CrossCameraPoints,
    epipolar_distances,
    match_across_cameras,
)
from service.calibration import load_caliscope_toml

RECORDING = Path(__file__).resolve().parents[2] / "shared" / "data" / "multicam2d_caliscope_charuco" / "4_cam_recording"


@pytest.fixture(scope="module")
def cameras():
    return load_caliscope_toml(RECORDING / "camera_array.toml")  # metres


def _synthetic_scene(cameras, rng, n_points=30, min_separation_px=8.0):
    """Random points around the board region (metres), visible in every camera and well separated in each image."""
    centre, spread = np.array([0.08, 0.13, 0.87]), np.array([0.15, 0.1, 0.15])
    points = np.empty((0, 3))
    while len(points) < n_points:
        candidate = centre + rng.uniform(-1, 1, 3) * spread
        trial = np.vstack([points, candidate])
        pix = [cam.project(trial) for cam in cameras]
        if not all(cam.in_image(p[-1:])[0] for cam, p in zip(cameras, pix)):
            continue
        if len(points) and min(np.linalg.norm(p[:-1] - p[-1], axis=1).min() for p in pix) < min_separation_px:
            continue
        points = trial
    return points


def test_epipolar_distance_is_zero_for_true_correspondences(cameras):
    rng = np.random.default_rng(0)
    points = _synthetic_scene(cameras, rng, n_points=10)
    a, b = cameras[0], cameras[2]
    dist = epipolar_distances(a, b, a.undistort(a.project(points)), b.undistort(b.project(points)))
    assert dist.shape == (10, 10)
    assert np.diag(dist).max() < 1e-6


def test_synthetic_points_recovered_with_all_views(cameras):
    rng = np.random.default_rng(1)
    truth = _synthetic_scene(cameras, rng)
    detections, truth_index = [], []
    for cam in cameras:
        pix = cam.project(truth) + rng.normal(0, 0.3, (len(truth), 2))
        perm = rng.permutation(len(truth))  # detection d of this camera is point perm[d]
        detections.append(pix[perm])
        truth_index.append(np.argsort(perm))  # point p -> its detection index
    result = match_across_cameras(cameras, detections)
    assert isinstance(result, CrossCameraPoints)
    expected_views = np.column_stack(truth_index)  # (P, C)
    for p, point in enumerate(truth):
        match = np.flatnonzero((result.views == expected_views[p]).all(axis=1))
        assert len(match) == 1, f"point {p} not recovered with all 4 views"
        assert np.linalg.norm(result.points[match[0]] - point) < 0.005
    assert len(result.points) == len(truth)  # no ghosts survive when every point has 4 views
    assert (result.reprojection_rms <= 2.0).all()

    offsets = np.cumsum([0] + [len(d) for d in detections])
    resources = result.resources(offsets)
    assert resources.shape == (len(truth), offsets[-1])
    assert (resources.sum(axis=1) == 4).all() and (resources.sum(axis=0) == 1).all()


def test_empty_and_single_camera_inputs(cameras):
    empty = match_across_cameras(cameras, [np.empty((0, 2))] * len(cameras))
    assert empty.points.shape == (0, 3) and empty.views.shape == (0, len(cameras))
    one = match_across_cameras(cameras, [np.array([[600.0, 300.0]])] + [np.empty((0, 2))] * 3)
    assert len(one.points) == 0


def _real_frames(cameras):
    data = np.genfromtxt(RECORDING / "xy.csv", delimiter=",", names=True)
    index = {int(cam.name.removeprefix("cam_")): c for c, cam in enumerate(cameras)}
    for sync in np.unique(data["sync_index"]):
        frame = data[data["sync_index"] == sync]
        detections, keypoints = [], []
        for cam_id, c in sorted(index.items(), key=lambda kv: kv[1]):
            rows = frame[frame["cam_id"] == cam_id]
            detections.append(np.column_stack([rows["img_loc_x"], rows["img_loc_y"]]))
            keypoints.append(rows["keypoint_id"].astype(int))
        yield detections, keypoints


def test_real_charuco_corners_recovered(cameras):
    rng = np.random.default_rng(2)
    recovered = fully = corners = kept = mixed = 0
    elapsed, n_frames = 0.0, 0
    for detections, keypoints in _real_frames(cameras):
        perms = [rng.permutation(len(d)) for d in detections]
        detections = [d[p] for d, p in zip(detections, perms)]
        keypoints = [k[p] for k, p in zip(keypoints, perms)]
        start = time.perf_counter()
        result = match_across_cameras(cameras, detections)
        elapsed += time.perf_counter() - start
        n_frames += 1

        ids = np.full(result.views.shape, -1)
        for c, k in enumerate(keypoints):
            used = result.views[:, c] >= 0
            ids[used, c] = k[result.views[used, c]]
        labels = [set(row[row >= 0].tolist()) for row in ids]
        agreeing = [next(iter(s)) for s in labels if len(s) == 1]
        kept += len(labels)
        mixed += sum(len(s) > 1 for s in labels)

        seen_by = {}
        for c, k in enumerate(keypoints):
            for kp in k.tolist():
                seen_by.setdefault(kp, set()).add(c)
        full = {next(iter(s)) for s, row in zip(labels, ids) if len(s) == 1
                and set(np.flatnonzero(row >= 0).tolist()) == seen_by[next(iter(s))]}
        for kp, cams_seeing in seen_by.items():
            if len(cams_seeing) >= 2:
                corners += 1
                recovered += kp in agreeing
                fully += kp in full
    recovered_fraction, mixed_fraction = recovered / corners, mixed / kept
    print(f"\nreal caliscope: {n_frames} frames, {corners} corners seen by >= 2 cameras; "
          f"recovered {recovered_fraction:.2%} (with all their views {fully / corners:.2%}); "
          f"kept points {kept}, mixing keypoint_ids {mixed_fraction:.2%}; "
          f"{1000 * elapsed / n_frames:.1f} ms per frame")
    assert recovered_fraction >= 0.99
    assert mixed_fraction <= 0.10
