"""per-camera association: each marker tracked in each camera's image, then triangulated.

Small cases against brute force and exact geometry, then CMU 85_02 end to end through the
real Pose2Sim rig (0.5 px noise, 3 px merging, 10 % occlusion in 15-frame bursts, 2 clutter
points per camera), and a resumed run against an uninterrupted one.
"""

from dataclasses import replace

import numpy as np
import pytest
from capture_fixtures import camera_capture, capture_of, seen_once_in_frame0, simulated_cmu
from windows import assert_feasible, brute_force

from formulations.cameras.camera import Camera
from formulations.cameras.per_camera.advance import advance_state
from formulations.cameras.per_camera.candidates import per_camera_candidates
from formulations.cameras.per_camera.gating import PerCameraGating
from formulations.cameras.per_camera.guide import per_camera_guide
from formulations.cameras.per_camera.locate import FrameViews, LocatedMarkers, locate_markers
from formulations.cameras.per_camera.reacquire import locate_with_reacquisition
from formulations.cameras.rig import Rig
from formulations.markers.state import MarkerState
from formulations.methods.ilp import Ilp
from formulations.methods.lp_l1 import LpL1
from formulations.window.build import build_window
from service.capture.capture import LabelingOptions
from service.evaluation.camera_scores import camera_scores
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.cloud import MARKER_COSTS
from service.labeling.outcome import WindowOutcome

K = [[1000.0, 0, 960], [0, 1000.0, 540], [0, 0, 1]]


def ring(n_cameras: int = 4) -> list[Camera]:
    """Cameras 3 m from the origin, looking at it, spread around the vertical axis."""
    return [
        Camera.from_rvec(K, np.zeros(5), [0.0, 2 * np.pi * c / n_cameras, 0.0], [0.0, 0.0, 3000.0], (1920, 1080), f"c{c}")
        for c in range(n_cameras)
    ]


def test_per_camera_window_lp_is_the_brute_force_optimum_for_crossing_markers():
    camera = ring(1)
    # Two markers cross in the image (x towards each other, 8 mm apart in y), plus clutter.
    steps = np.arange(5)[:, None]
    a = np.column_stack([-30 + 15 * steps[:, 0], np.zeros(5), np.zeros(5)])
    b = np.column_stack([30 - 15 * steps[:, 0], np.full(5, 8.0), np.zeros(5)])
    state = MarkerState.from_first_frame(np.stack([a[0], b[0]])).advance(np.stack([a[1], b[1]]), np.ones(2, bool))
    rng = np.random.default_rng(3)
    pixels = []
    for f in range(2, 5):
        found = np.concatenate([camera[0].project(np.stack([a[f], b[f]])), [[960 + rng.uniform(-15, 15), 540.0]]])
        pixels.append([found[rng.permutation(3)]])
    rig = Rig.of(camera)
    frames = [FrameViews(pixels=frame, normalised=[camera[0].undistort(frame[0])]) for frame in pixels]
    gating = PerCameraGating()
    guide = per_camera_guide(state, rig, frames, gating)
    window = per_camera_candidates(state, rig, guide, frames, gating)
    problem, node_candidate = build_window(window.candidates, MARKER_COSTS)
    assert problem.conflict_groups.shape[0] >= 3  # both markers gate every detection of every frame

    optimum, best = brute_force(problem)
    for formulation in (LpL1(), Ilp()):
        solution = formulation.solve(problem)
        assert_feasible(problem, solution.path)
        assert solution.cost == pytest.approx(optimum, abs=1e-6)
    views = window.views(node_candidate, best)  # (M, N, C)
    truth = [
        [np.argmin(np.linalg.norm(frame[0] - camera[0].project(p[f + 2][None]), axis=1)) for p in (a, b)]
        for f, frame in enumerate(pixels)
    ]
    assert views.shape == (3, 2, 1)
    np.testing.assert_array_equal(views[:, :, 0], truth)  # through the crossing, each keeps its own


def test_a_wrong_camera_assignment_is_dropped_and_the_rest_triangulated():
    cameras = ring(4)
    point = np.array([[40.0, -25.0, 60.0]])
    pixels = np.stack([camera.project(point) for camera in cameras], axis=1)  # (1, 4, 2)
    wrong = pixels.copy()
    wrong[0, 2] += [7.0, -5.0]  # camera 2 tracked the neighbouring blob
    # Without the check the wrong view spoils the point and reprojects badly.
    rig = Rig.of(cameras)
    spoiled = rig.triangulate(rig.undistort(wrong))
    assert np.linalg.norm(spoiled - point) > 5.0
    assert np.nanmax(rig.errors(spoiled, wrong)) > 2.0

    located = locate_markers(rig, wrong, rig.undistort(wrong), point + 30.0, max_error_px=2.0)
    np.testing.assert_array_equal(located.kept, [[True, True, False, True]])
    np.testing.assert_allclose(located.point, point, atol=1e-6)


def test_two_disagreeing_views_keep_the_one_the_prediction_supports():
    cameras = ring(4)
    point = np.array([[0.0, 50.0, -20.0]])
    pixels = np.full((1, 4, 2), np.nan)
    pixels[0, [0, 1]] = [camera.project(point)[0] for camera in cameras[:2]]
    pixels[0, 1] += [0.0, 30.0]  # off the epipolar line: the rays do not meet
    rig = Rig.of(cameras)
    located = locate_markers(rig, pixels, rig.undistort(pixels), point + [3.0, 0.0, 0.0], max_error_px=2.0)
    np.testing.assert_array_equal(located.kept, [[True, False, False, False]])
    # One view: the point of camera 0's ray nearest the prediction, so only along-ray error remains.
    assert np.linalg.norm(located.point - point) < 3.0 + 1e-6
    assert rig.errors(located.point, pixels)[0, 0] < 1e-6


def test_no_view_leaves_the_prediction():
    cameras = ring(4)
    prediction = np.array([[1.0, 2.0, 3.0]])
    nothing = np.full((1, 4, 2), np.nan)
    located = locate_markers(Rig.of(cameras), nothing, nothing, prediction)
    assert located.n_views[0] == 0
    np.testing.assert_array_equal(located.point, prediction)


def _body_state(cameras: list[Camera]) -> tuple[MarkerState, np.ndarray]:
    """Five markers of a rigid body, seen by every camera for ten frames (distances learned)."""
    body = np.array([[0.0, 0, 0], [80, 0, 0], [0, 90, 0], [0, 0, 70], [60, 60, 40]])
    state = MarkerState.from_first_frame(body, n_neighbours=4)
    for f in range(1, 11):
        state = state.advance(body + [2.0 * f, 0, 0], np.ones(len(body), bool))
    return state, body + [22.0, 0, 0]


def _frame(cameras: list[Camera], detections: list[np.ndarray]) -> FrameViews:
    return FrameViews(pixels=detections, normalised=[camera.undistort(found) for camera, found in zip(cameras, detections)])


def test_a_single_view_marker_gets_its_second_view_from_the_epipolar_band():
    cameras = ring(4)
    state, frame = _body_state(cameras)
    detections = [camera.project(frame) for camera in cameras]
    views = np.tile(np.arange(5)[:, None], (1, 4))
    views[0] = [0, -1, -1, -1]  # marker 0 was tracked by camera 0 only
    # Marker 0's detections (index 0) lie free in cameras 1-3, and camera 1 also has a
    # clutter blob on marker 0's epipolar line, 150 mm deeper along camera 0's ray.
    origin, direction = cameras[0].centre, cameras[0].direction(cameras[0].undistort(detections[0][:1]))
    decoy = cameras[1].project(origin + (np.linalg.norm(frame[0] - origin) + 150.0) * direction)
    detections[1] = np.concatenate([detections[1], decoy])
    prediction = frame + [0.0, 0.0, 120.0]  # a drifted prediction does not matter: the body does
    rig, gating = Rig.of(cameras), PerCameraGating(max_reprojection_px=2.0, max_shape_mm=20.0)
    located, kept = locate_with_reacquisition(rig, _frame(cameras, detections), views, state, prediction, gating)
    assert (kept[0] >= 0).sum() == 2 and kept[0, 0] == 0 and kept[0][kept[0] >= 0][1] == 0  # not the decoy (5)
    np.testing.assert_array_equal(kept[1:], views[1:])
    np.testing.assert_allclose(located.point[0], frame[0], atol=1e-6)
    # Without marker 0's true detections the decoy alone is refused: it breaks the body's distances.
    alone = [found if c == 0 else found[1:] for c, found in enumerate(detections)]
    shifted = np.where(np.arange(4) > 0, np.where(views > 0, views - 1, views), views)
    _, kept = locate_with_reacquisition(rig, _frame(cameras, alone), shifted, state, prediction, gating)
    np.testing.assert_array_equal(kept[0], [0, -1, -1, -1])


def test_scores_count_a_marker_correct_only_with_its_own_detections():
    marker_detection = np.array([[[0, 1], [0, 1]], [[1, 0], [0, -1]]])  # (F=2, C=2, N=2)
    views = np.array([[[0, 0], [1, 1]], [[1, 0], [0, -1]]])  # (F, N, C)
    views_wrong = views.copy()
    views_wrong[1, 0, 1] = 1  # marker 0 took camera 1's detection 1: nobody's (clutter)
    views_none = views.copy()
    views_none[1, 0] = -1
    truth = np.zeros((2, 2, 3))
    result = LabeledTrajectories(["a", "b"], truth.copy(), np.zeros((2, 2), bool), 100.0, filled=np.full((2, 2, 3), np.nan))
    # frame 1: marker a is seen by both cameras; b by camera 0 only, and rightly labeled from it,
    # so scored too (a label written); frame 0 is the user's
    assert camera_scores(marker_detection, truth, result, views).label_accuracy == 1.0
    assert camera_scores(marker_detection, truth, result, views_wrong).label_accuracy == 0.5
    assert camera_scores(marker_detection, truth, result, views_none).label_accuracy == 0.5
    assert camera_scores(marker_detection, truth, result, views).marker_frames == 2
    views_b_none = views.copy()
    views_b_none[1, 1] = -1  # b left unlabeled: seen by one camera, no 3D point, not a miss
    assert camera_scores(marker_detection, truth, result, views_b_none).marker_frames == 1


def test_per_camera_labels_cmu_85_02_through_the_pose2sim_rig():
    cameras, simulated = simulated_cmu(300)
    capture = capture_of(cameras, simulated)
    labeling = CaptureLabeling(capture, LabelingOptions(association="per-camera"))
    outcomes = list(labeling.windows())
    result = labeling.result(outcomes)
    scores = camera_scores(simulated.marker_detection, simulated.truth.positions, result,
                           labeling.views(outcomes))
    assert scores.marker_frames > 0.9 * 299 * len(capture.names)
    assert scores.label_accuracy >= 0.999
    assert scores.rmse_mm <= 3.0
    # Occluded markers carry their predicted position, flagged by `occluded`.
    assert np.isfinite(result.filled[result.occluded]).all() and np.isnan(result.filled[~result.occluded]).all()
    assert np.isnan(result.positions[result.occluded]).all() and np.isfinite(result.positions[~result.occluded]).all()
    assert scores.rmse_mm < scores.filled_rmse_mm < 100.0


def test_frame_0_has_the_labeled_markers_detections_and_the_best_view_ignores_the_camera_order():
    """Frame 0 had no views: every camera looked blind there, the best view of every marker
    was the first camera listed, and the choice carried on (86-167 marker-frames up to frame
    75 of a 150-frame take changed with the order of the cameras)."""
    cameras, simulated = simulated_cmu(30, markers=12)
    capture, expected = seen_once_in_frame0(cameras, simulated, 3)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10, association="per-camera"))
    outcomes = list(labeling.windows())
    np.testing.assert_array_equal(labeling.views(outcomes)[0], expected)
    result = labeling.result(outcomes)
    np.testing.assert_array_equal(result.positions[0], capture.first_frame)  # a single view does not move it
    order = [2, 0, 3, 1]
    reordered = replace(capture, cameras=[cameras[c] for c in order],
                        detections=[[frame[c] for c in order] for frame in capture.detections])
    again, _ = CaptureLabeling(reordered, LabelingOptions(window=10, association="per-camera")).label()
    assert again.best_view_names() == result.best_view_names()


def test_resumed_per_camera_labeling_equals_the_uninterrupted_run():
    capture = camera_capture(60)
    labeling = CaptureLabeling(capture, LabelingOptions(association="per-camera"))
    outcomes = list(labeling.windows())
    assert len(outcomes) == 4
    stored = WindowOutcome.from_bytes(outcomes[1].to_bytes())
    for name in ("point_index", "filled", "views", "positions"):
        np.testing.assert_array_equal(getattr(stored, name), getattr(outcomes[1], name))
    resumed = list(CaptureLabeling(capture, LabelingOptions(association="per-camera")).windows(after=stored))
    assert [o.index for o in resumed] == [2, 3]
    for a, b in zip(resumed, outcomes[2:]):
        for name in ("filled", "views", "positions"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        np.testing.assert_array_equal(a.state.position, b.state.position)
    full = labeling.result(outcomes)
    again = labeling.result(outcomes[:2] + resumed)
    np.testing.assert_array_equal(full.positions, again.positions)


def test_locate_markers_equals_the_brute_force_over_every_subset():
    cameras, rig = ring(4), Rig.of(ring(4))
    rng = np.random.default_rng(11)
    points = rng.uniform(-300, 300, (60, 3))
    pixels = np.stack([camera.project(points) for camera in cameras], axis=1) + rng.normal(0, 0.4, (60, 4, 2))
    wrong = rng.random((60, 4)) < 0.25
    pixels[wrong] += rng.normal(0, 6, (wrong.sum(), 2))  # views of a neighbouring blob
    pixels[rng.random((60, 4)) < 0.2] = np.nan
    prediction = points + rng.normal(0, 20, points.shape)
    located = locate_markers(rig, pixels, rig.undistort(pixels), prediction, max_error_px=2.0)
    for n in range(len(points)):
        best = None  # largest consistent subset, then nearest the prediction
        for mask in range(1, 16):
            subset = [c for c in range(4) if mask >> c & 1 and np.isfinite(pixels[n, c]).all()]
            if len(subset) < 2 or len(subset) != bin(mask).count("1"):
                continue
            used = np.full((1, 4, 2), np.nan)
            used[0, subset] = pixels[n, subset]
            point = rig.triangulate(rig.undistort(used))
            if np.nanmax(rig.errors(point, used)) <= 2.0:
                key = (-len(subset), np.linalg.norm(point[0] - prediction[n]))
                best = min(best, (key, subset, point[0]), key=lambda b: b[0]) if best else (key, subset, point[0])
        if best is not None:
            assert sorted(np.flatnonzero(located.kept[n])) == best[1]
            np.testing.assert_allclose(located.point[n], best[2], atol=1e-6)
        else:
            assert located.n_views[n] <= 1


def test_a_two_view_point_the_body_rejects_is_split_and_the_marker_reacquired():
    cameras = ring(4)
    state, frame = _body_state(cameras)
    detections = [camera.project(frame) for camera in cameras]
    # Camera 1 gave marker 0 a clutter blob on its epipolar line, 300 mm deeper along
    # camera 0's ray: the pair reprojects exactly, but sits 300 mm off the body.
    origin, direction = cameras[0].centre, cameras[0].direction(cameras[0].undistort(detections[0][:1]))
    decoy = cameras[1].project(origin + (np.linalg.norm(frame[0] - origin) + 300.0) * direction)
    detections[1] = np.concatenate([detections[1], decoy])
    views = np.tile(np.arange(5)[:, None], (1, 4))
    views[0] = [0, 5, -1, -1]
    rig = Rig.of(cameras)
    strict = PerCameraGating(max_pair_shape_mm=60.0)
    located, kept = locate_with_reacquisition(rig, _frame(cameras, detections), views, state, frame, strict)
    assert kept[0, 1] == -1 and kept[0, 0] == 0 and (kept[0] >= 0).sum() == 2  # the decoy gone, a true pair found
    np.testing.assert_allclose(located.point[0], frame[0], atol=1e-6)
    lenient = PerCameraGating(max_pair_shape_mm=np.inf)
    _, kept = locate_with_reacquisition(rig, _frame(cameras, detections), views, state, frame, lenient)
    np.testing.assert_array_equal(kept[0], [0, 5, -1, -1])  # without the body check the decoy pair stands


def test_a_single_view_marker_is_re_anchored_on_its_ray_but_not_seen():
    cameras = ring(4)
    state, frame = _body_state(cameras)
    point = frame + [0.0, 0.0, 30.0]
    kept = np.ones((5, 4), bool)
    kept[2] = [False, True, False, False]
    after = advance_state(state, LocatedMarkers(point=point, kept=kept))
    plain = state.advance(point, kept.sum(axis=1) >= 2)
    assert after.unseen[2] == 1 and not after.visible[2]
    np.testing.assert_array_equal(after.velocity, plain.velocity)
    np.testing.assert_array_equal(after.position[2], point[2])
    np.testing.assert_array_equal(after.anchor[2], point[2])
    np.testing.assert_array_equal(after.anchor_neighbours[2], point[state.neighbours[2]])
    np.testing.assert_array_equal(np.delete(after.position, 2, axis=0), np.delete(plain.position, 2, axis=0))
    # Next frame it follows its neighbours' motion from the ray point, not from its old anchor.
    moved = after.advance(point + [5.0, 0, 0], kept.sum(axis=1) >= 2)
    np.testing.assert_allclose(moved.predict()[2], point[2] + [10.0, 0, 0], atol=1e-6)
