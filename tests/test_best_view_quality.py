"""View quality of boxes and markers (best view), and the best view of camera-mode jobs."""

import itertools

import numpy as np
import pytest
from capture_fixtures import camera_capture, points_capture

from formulations.best_view import box_quality, box_truncation, marker_quality
from formulations.cameras.camera import Camera
from service.best_view.markers import MarkerViewChoice
from service.capture.capture import Capture, LabelingOptions
from service.errors import InputError
from service.io.formats import write_labeled
from service.io.formats.csv import read_csv_labeled
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling
from service.server.results import trajectories_from_bytes, trajectories_json, trajectories_to_bytes


def pixels_inside(box, width, height):
    """Unit pixels [x, x+1) x [y, y+1) of an integer box that lie in the image, counted one by one."""
    left, top, w, h = box
    return sum(0 <= x < width and 0 <= y < height for x in range(left, left + w) for y in range(top, top + h))


def test_truncation_counts_the_pixels_outside_the_image():
    width, height = 7, 5
    for box in itertools.product(range(-3, 8, 2), range(-3, 6, 2), (1, 3, 6), (2, 4)):
        inside = pixels_inside(box, width, height)
        assert box_truncation(np.array(box, float), (width, height)) == pytest.approx(1 - inside / (box[2] * box[3]))
        assert box_quality(np.array(box, float), (width, height)) == pytest.approx(inside**2 / (box[2] * box[3]))


def test_a_missing_box_has_no_quality_and_sizes_broadcast_per_camera():
    boxes = np.array([[[0, 0, 10, 10], [np.nan] * 4], [[95, 0, 10, 10], [0, 0, 4, 5]]])
    quality = box_quality(boxes, np.array([[100, 100], [200, 50]]))
    np.testing.assert_allclose(quality, [[100, 0], [25, 20]])


def looking_at_origin(centre, name):
    """A camera at ``centre`` whose optical axis passes through the origin."""
    forward = -np.asarray(centre, float) / np.linalg.norm(centre)
    right = np.cross(forward, [0, 0, 1.0]) if abs(forward[2]) < 0.9 else np.cross(forward, [0, 1.0, 0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    R = np.stack([right, down, forward])
    return Camera(K=np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]]), distortion=np.zeros(5), R=R,
                  t=-R @ np.asarray(centre, float), image_size=(640, 480), name=name)


def test_marker_quality_is_size_times_visibility_times_facing():
    near, far, side = looking_at_origin([0, -2000, 0], "near"), looking_at_origin([0, 4000, 0], "far"), \
        looking_at_origin([3000, 0, 0], "side")
    # two markers either side of the origin along y: the first faces -y (the near camera), the second +y
    positions = np.array([[[0, -100.0, 0], [0, 100.0, 0]]])
    quality = marker_quality(positions, np.ones((1, 2, 3)), [near, far, side])
    size = lambda camera, x: 800.0 / (camera.R[2] @ x + camera.t[2])  # noqa: E731
    for k, x in enumerate(positions[0]):
        normal = x / np.linalg.norm(x)
        for b, camera in enumerate([near, far, side]):
            towards = camera.centre - x
            facing = 0.5 * (1 + normal @ towards / np.linalg.norm(towards))
            assert quality[0, k, b] == pytest.approx(size(camera, x) * facing)
    assert quality[0, 0, 0] > quality[0, 0, 1] and quality[0, 1, 1] > quality[0, 1, 0]
    hidden = marker_quality(positions, np.array([[[0, 1, 1], [1, 1, 0.5]]]), [near, far, side])
    assert hidden[0, 0, 0] == 0 and hidden[0, 1, 2] == pytest.approx(0.5 * quality[0, 1, 2])


def test_a_marker_behind_a_camera_or_unknown_has_no_quality():
    camera = looking_at_origin([0, -2000, 0], "c")
    quality = marker_quality(np.array([[[0, -2500.0, 0], [np.nan] * 3]]), np.ones((1, 2, 1)), [camera])
    np.testing.assert_array_equal(quality, 0.0)


def test_camera_jobs_carry_each_markers_best_view_through_json_csv_and_storage(tmp_path):
    capture = camera_capture(40, markers=12)
    labels, _ = CaptureLabeling(capture, LabelingOptions(window=10, best_view_window=8)).label()
    names = [camera.name for camera in capture.cameras]
    assert labels.view_names == names
    assert labels.best_view.shape == (40, 12) and set(np.unique(labels.best_view)) <= set(range(len(names)))
    document = trajectories_json(labels)
    assert document["best_view"][7][3] == names[labels.best_view[7, 3]]
    back = trajectories_from_bytes(trajectories_to_bytes(labels))
    np.testing.assert_array_equal(back.best_view, labels.best_view)
    write_labeled(tmp_path / "labels.csv", labels)
    table = read_csv_labeled(tmp_path / "labels.csv")
    assert [table.view_names[i] for i in table.best_view[12]] == [names[i] for i in labels.best_view[12]]


def test_a_larger_switch_cost_switches_less_in_a_camera_job():
    capture = camera_capture(40, markers=12)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10))
    outcomes = list(labeling.windows())
    eager = CaptureLabeling(capture, LabelingOptions(window=10, best_view_switch_cost=0.0)).result(outcomes)
    steady = CaptureLabeling(capture, LabelingOptions(window=10, best_view_switch_cost=100.0)).result(outcomes)
    assert np.count_nonzero(np.diff(steady.best_view, axis=0)) == 0 < np.count_nonzero(np.diff(eager.best_view, axis=0))


def test_a_camera_that_detects_nothing_is_never_a_best_view():
    """With a clear ray an undetected camera still had P_D 0.9: a camera whose detections were
    all missing was named the best view of 13 % of the marker-frames."""
    capture = camera_capture(30, markers=12)
    blind = 1  # without the rule the best view of a quarter of these marker-frames
    detections = [[np.empty((0, 2)) if c == blind else pixels for c, pixels in enumerate(frame)]
                  for frame in capture.detections]
    capture = Capture(capture.names, capture.first_frame, capture.rate, cameras=capture.cameras, detections=detections)
    labels, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    assert labels.view_names[blind] == capture.cameras[blind].name
    assert not (labels.best_view == blind).any() and (labels.best_view >= 0).all()


def test_a_camera_that_goes_blind_is_left_even_where_no_camera_shows_the_marker():
    """docs/cameras.md: the best view never names a camera in a frame where it took no marker.
    Camera b shows a limb's marker best in frame 0, then takes nothing; camera a takes the
    others but its ray to the marker crosses the limb (quality 0). Every camera then cost 1,
    staying on b tied with a switch (lambda = 1) and b stayed the best view of a blind camera."""
    limb, hidden = _limb()
    through, clear = looking_at_origin([-1500, -1000, 0], "a"), looking_at_origin([1500, 1000, 0], "b")
    positions = np.repeat(limb[None], 4, axis=0)
    labels = LabeledTrajectories([f"m{i}" for i in range(len(limb))], positions, np.zeros((4, len(limb)), bool), 120.0)
    views = np.zeros((4, len(limb), 2), dtype=int)
    views[0, hidden, 0] = -1  # frame 0: only b sees the marker
    views[1:, :, 1] = -1  # then b takes nothing
    views[1:, hidden, 0] = -1  # and a never sees it through the limb
    chosen = MarkerViewChoice([through, clear], switch_cost=1.0, window=30).attach(labels, views).best_view
    assert chosen[:, hidden].tolist() == [1, 0, 0, 0]
    assert (chosen[1:] == 0).all()


def _limb() -> tuple[np.ndarray, int]:
    """Markers ringing a limb along z, and the index of the one at (0, 50, 20)."""
    angles = np.deg2rad(np.arange(0, 360, 45))
    limb = np.array([[50 * np.cos(a), 50 * np.sin(a), z] for z in (-60.0, -20.0, 20.0, 60.0) for a in angles])
    return limb, next(i for i, x in enumerate(limb) if np.allclose(x, [0, 50, 20]))


def test_point_jobs_have_no_best_view(tmp_path):
    labels, _ = CaptureLabeling(points_capture(12), LabelingOptions(window=6)).label()
    assert labels.best_view.size == 0 and trajectories_json(labels)["best_view"] is None
    write_labeled(tmp_path / "labels.csv", labels)
    assert "best_view" not in (tmp_path / "labels.csv").read_text().splitlines()[0]


@pytest.mark.parametrize("fields,message", [
    ({"best_view_switch_cost": -1.0}, "best_view_switch_cost"),
    ({"best_view_window": 0}, "best_view_window"),
])
def test_bad_best_view_options_are_one_line(fields, message):
    with pytest.raises(InputError, match=message):
        LabelingOptions(**fields)
    with pytest.raises(InputError, match=message):  # the view choice checks what is built past the options
        MarkerViewChoice(camera_capture(5, markers=4).camera_frames()[0], fields.get("best_view_switch_cost", 1.0),
                         fields.get("best_view_window", 30))


def test_an_occluded_marker_is_best_seen_by_the_camera_whose_ray_clears_the_body():
    """A limb ringed by markers; one of them seen only by camera a in frame 0, then by none.
    With 0/1 visibility camera a shows it best in frame 0 and no camera after (qualities 0,
    so the view stays); the occlusion-aware P_D sees that the ray to camera a crosses the
    limb (a saw it regardless in frame 0) and the ray to camera b does not."""
    limb, hidden = _limb()
    through, clear = looking_at_origin([-1500, -1000, 0], "a"), looking_at_origin([1500, 1000, 0], "b")
    positions = np.repeat(limb[None], 3, axis=0)
    measured, filled = positions.copy(), np.full_like(positions, np.nan)
    measured[1:, hidden], filled[1:, hidden] = np.nan, limb[hidden]
    views = np.zeros((3, len(limb), 2), dtype=int)
    views[1:, hidden], views[0, hidden, 1] = -1, -1
    labels = LabeledTrajectories([f"m{i}" for i in range(len(limb))], measured, np.isnan(measured[..., 0]), 120.0,
                                 filled=filled)
    chosen = MarkerViewChoice([through, clear], switch_cost=0.0, window=1).attach(labels, views).best_view
    assert (chosen[:, hidden] == 1).all()
    alone = MarkerViewChoice([through], switch_cost=0.0, window=1)
    visibility = alone._visibility(measured, np.where(np.isnan(measured), filled, measured), views[..., :1] >= 0)
    assert visibility[1, hidden, 0] < 0.05 and (visibility[:, np.arange(len(limb)) != hidden] == 1).all()
