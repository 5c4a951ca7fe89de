"""Cross-camera matching: synthetic points through the real caliscope cameras, then real ChArUco corners."""

import time
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from formulations.cameras.cross_camera.block import BlockDetections
from formulations.cameras.cross_camera.matching import CrossCameraPoints, epipolar_distances, match_frames
from formulations.cameras.rig import Rig
from service.io.calibration import load_caliscope_toml

RECORDING = Path(__file__).resolve().parents[2] / "shared" / "data" / "multicam2d_caliscope_charuco" / "4_cam_recording"


@pytest.fixture(scope="module")
def cameras():
    return load_caliscope_toml(RECORDING / "camera_array.toml")  # metres


def match_one(cameras, detections) -> CrossCameraPoints:
    """The candidate points of one frame: ``match_frames`` of a block of that frame alone."""
    return match_frames(cameras, [detections])[0]


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
    result = match_one(cameras, detections)
    assert isinstance(result, CrossCameraPoints)
    expected_views = np.column_stack(truth_index)  # (P, C)
    for p, point in enumerate(truth):
        match = np.flatnonzero((result.views == expected_views[p]).all(axis=1))
        assert len(match) == 1, f"point {p} not recovered with all 4 views"
        assert np.linalg.norm(result.points[match[0]] - point) < 0.005
    assert len(result.points) == len(truth)  # no ghosts survive when every point has 4 views
    assert (result.reprojection_rms <= 2.0).all()

    offsets = np.cumsum([0] + [len(d) for d in detections])
    resources = result.resources(offsets[:-1], offsets[-1])
    assert resources.shape == (len(truth), offsets[-1])
    assert (resources.sum(axis=1) == 4).all() and (resources.sum(axis=0) == 1).all()


def test_empty_and_single_camera_inputs(cameras):
    empty = match_one(cameras, [np.empty((0, 2))] * len(cameras))
    assert empty.points.shape == (0, 3) and empty.views.shape == (0, len(cameras))
    one = match_one(cameras, [np.array([[600.0, 300.0]])] + [np.empty((0, 2))] * 3)
    assert len(one.points) == 0


def _subsets(rng, n_points, n_cams, min_views):
    """(P, C) bool: random camera subsets of at least ``min_views`` cameras."""
    seen = rng.random((n_points, n_cams)) < 0.7
    for p in range(n_points):
        seen[p, rng.permutation(n_cams)[:min_views]] = True
    return seen


def _least_squares_point(cameras, pixels, start):
    """Gold standard: the point minimising the pixel reprojection error over the views given (NaN: unseen)."""
    seen = np.flatnonzero(np.isfinite(pixels[:, 0]))
    residual = lambda x: np.concatenate([cameras[c].project(x[None])[0] - pixels[c] for c in seen])  # noqa: E731
    return least_squares(residual, start, xtol=1e-12, ftol=1e-12).x


def test_block_triangulation_is_least_squares_in_pixels(cameras):
    rng = np.random.default_rng(3)
    truth = _synthetic_scene(cameras, rng, n_points=20)
    seen = _subsets(rng, len(truth), len(cameras), min_views=2)
    exact = [cam.project(truth) for cam in cameras]
    block = BlockDetections.of(cameras, [exact])
    views = np.where(seen, np.arange(len(truth))[:, None] + block.offsets[0], -1)
    assert np.abs(block.triangulate(views) - truth).max() < 1e-9  # exact detections: the point itself

    noisy = [p + rng.normal(0, 0.5, p.shape) for p in exact]
    pixels = np.where(seen[..., None], np.stack(noisy, axis=1), np.nan)
    ours = BlockDetections.of(cameras, [noisy]).triangulate(views)
    rig = Rig.of(cameras)
    dlt = rig.triangulate(rig.undistort(pixels))
    best = np.array([_least_squares_point(cameras, pix, start) for pix, start in zip(pixels, dlt)])

    def rms(points):
        return np.sqrt(np.nanmean(rig.errors(points, pixels) ** 2, axis=1))

    # Weighting by depth brings the linear solve close to the pixel optimum, closer than the DLT.
    assert (rms(ours) - rms(best)).max() < 0.05
    assert np.abs(rms(ours) - rms(best)).mean() < np.abs(rms(dlt) - rms(best)).mean()


def test_leave_one_out_is_the_distance_to_the_point_from_the_other_views(cameras):
    rng = np.random.default_rng(4)
    truth = _synthetic_scene(cameras, rng, n_points=15)
    seen = _subsets(rng, len(truth), len(cameras), min_views=3)
    noisy = [cam.project(truth) + rng.normal(0, 0.5, (len(truth), 2)) for cam in cameras]
    pixels = np.where(seen[..., None], np.stack(noisy, axis=1), np.nan)
    block = BlockDetections.of(cameras, [noisy])
    views = np.where(seen, np.arange(len(truth))[:, None] + block.offsets[0], -1)
    left_out = np.array([rng.choice(np.flatnonzero(s)) for s in seen])
    distance = block.leave_one_out(views, left_out, block.rig.depth(block.triangulate(views)))
    expected = np.empty(len(truth))
    for p, c in enumerate(left_out):  # brute force: the pixel optimum from the other views, projected into c
        others = pixels[p].copy()
        others[c] = np.nan
        point = _least_squares_point(cameras, others, truth[p])
        expected[p] = np.linalg.norm(cameras[c].project(point[None])[0] - pixels[p, c])
    # The linear solve is the pixel optimum up to the lens distortion, strong in these webcams.
    assert np.abs(distance - expected).max() < 0.15
    assert np.abs(distance - expected).mean() < 0.05


def _on_ray(cameras, camera, pixel, avoid, rng):
    """A point on ``camera``'s ray through ``pixel``, in every image and > 10 px from ``avoid`` elsewhere."""
    origin = cameras[camera].centre
    direction = cameras[camera].direction(cameras[camera].undistort(np.asarray(pixel)[None]))[0]
    for depth in rng.permutation(np.linspace(0.5, 1.4, 91)):
        point = origin + depth * direction
        ok = all(cam.in_image(cam.project(point[None]))[0] for cam in cameras)
        far = all(np.linalg.norm(cam.project(point[None])[0] - cam.project(avoid[None])[0]) > 10
                  for c, cam in enumerate(cameras) if c != camera)
        if ok and far:
            return point
    raise AssertionError("no such point")


def _match_two(cameras, a, b, a_views, b_views, merged_in=None):
    """Detections of points a and b in the cameras where each is seen; returns the match and their views."""
    detections, expected = [], np.full((2, len(cameras)), -1)
    for c, cam in enumerate(cameras):
        pix = []
        for k, (point, seen) in enumerate(((a, a_views), (b, b_views))):
            if c in seen:
                if c == merged_in and k == 1:
                    expected[1, c] = expected[0, c]  # the blob of both
                    continue
                expected[k, c] = len(pix)
                pix.append(cam.project(point[None])[0])
        detections.append(np.array(pix).reshape(-1, 2))
    return match_one(cameras, detections), expected


def test_a_detection_grown_onto_a_neighbour_goes_back_to_its_own_point(cameras):
    # a is hidden from camera 3, b from camera 0, where b would project 1 px beside a's detection:
    # b's point grows into camera 0 with a's detection. Ranked by views alone, that 4-view point
    # kept a's detection and dropped a. a's other views predict it exactly; b's, 1 px away.
    rng = np.random.default_rng(5)
    a = np.array([0.08, 0.13, 0.87])
    b = _on_ray(cameras, 0, cameras[0].project(a[None])[0] + [1.0, 0.0], a, rng)
    result, expected = _match_two(cameras, a, b, a_views={0, 1, 2}, b_views={1, 2, 3})
    assert sorted(map(tuple, result.views.tolist())) == sorted(map(tuple, expected.tolist()))


def test_a_merged_blob_is_not_contested_by_both_markers(cameras):
    # a and b coincide in camera 3 (one detection for both): both are kept, and only one of them
    # uses the blob, so the window LP can label both.
    rng = np.random.default_rng(6)
    a = np.array([0.08, 0.13, 0.87])
    b = _on_ray(cameras, 3, cameras[3].project(a[None])[0], a, rng)
    result, expected = _match_two(cameras, a, b, a_views={0, 1, 2, 3}, b_views={0, 1, 2, 3}, merged_in=3)
    assert len(result.points) == 2
    agrees = [((result.views < 0) | (result.views == row)).all(axis=1) for row in expected]
    assert all(a.sum() == 1 for a in agrees) and (agrees[0] != agrees[1]).all()
    used = result.views[result.views >= 0]
    assert (result.views >= 0).sum() == 7 and len(used) == 7  # 4 + 3 views, the blob once
    assert ((result.views[:, 3] >= 0).sum()) == 1


def test_a_block_of_frames_matches_as_each_frame_alone(cameras):
    rng = np.random.default_rng(7)
    frames = []
    for _ in range(4):
        truth = _synthetic_scene(cameras, rng, n_points=12)
        frames.append([rng.permutation(np.vstack([cam.project(truth) + rng.normal(0, 0.3, (12, 2)),
                                                  rng.random((2, 2)) * cam.image_size]))[: rng.integers(8, 15)]
                       for cam in cameras])
    frames.append([np.empty((0, 2))] * len(cameras))
    block = match_frames(cameras, frames)
    assert len(block) == len(frames)
    for together, detections in zip(block, frames):
        alone = match_one(cameras, detections)
        assert np.array_equal(together.views, alone.views)
        assert np.allclose(together.points, alone.points) and np.allclose(together.reprojection_rms, alone.reprojection_rms)
    assert sum(len(m.points) for m in block[:4]) >= 4 * 8


def _real_frames(cameras):
    data = np.genfromtxt(RECORDING / "xy.csv", delimiter=",", names=True)
    index = {int(cam.name.removeprefix("cam_")): c for c, cam in enumerate(cameras)}
    for sync in np.unique(data["sync_index"]):
        frame = data[data["sync_index"] == sync]
        detections, keypoints = [], []
        for cam_id, _ in sorted(index.items(), key=lambda kv: kv[1]):
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
        result = match_one(cameras, detections)
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
