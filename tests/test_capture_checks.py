"""A capture built in Python is checked as a capture document is: one line naming the problem.

Before these checks each bad input below ran into numpy, scipy or ezc3d (a ckdtree
``'x' must be finite``, a broadcast error, a C++ abort writing a C3D at rate 0) or was
labeled silently into files the reader then refused.
"""

from __future__ import annotations

import numpy as np
import pytest

from formulations.cameras.camera import Camera
from service.capture.capture import Capture, LabelingOptions
from service.errors import InputError
from service.labeling.capture_labeling import CaptureLabeling

NAMES = ["A", "B", "C", "D"]
FIRST = np.array([[0.0, 0, 0], [100, 0, 0], [0, 100, 0], [0, 0, 100]])


def _frames(n: int = 6) -> list[np.ndarray]:
    return [FIRST + [2.0 * f, 0, 0] for f in range(n)]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"rate": 0}, "rate must be between"),
        ({"rate": -120.0}, "rate must be between"),
        ({"rate": float("nan")}, "rate must be a finite number"),
        ({"rate": "120"}, "rate must be a finite number"),
        ({"names": NAMES[:3] + ["A"]}, "names[3]: marker name 'A' appears twice"),
        ({"names": NAMES[:3] + [" "]}, "names[3]: a marker name must be a non-blank string"),
        ({"first_frame": FIRST[:3]}, "first_frame must be (4, 3)"),
        ({"points": [FIRST]}, "at least 2 frames"),
        ({"points": []}, "at least 2 frames"),
        ({"points": [FIRST, np.vstack([FIRST, [np.nan] * 3])]}, "points[1][4]: [nan, nan, nan] is not a finite"),
        ({"points": [FIRST, FIRST.T]}, "points[1]: points must be (P, 3), got shape (3, 4)"),
        ({"points": [FIRST, FIRST[:, :2]]}, "points[1]: points must be (P, 3), got shape (4, 2)"),
        ({"points": [FIRST, [[1.0, 2.0, 3.0], [1.0, 2.0]]]}, "points[1]: not an array of numbers"),
        ({"unnamed_markers": -1}, "unnamed_markers must be a whole number of at least 0"),
        ({"unnamed_markers": 1.5}, "unnamed_markers must be a whole number"),
        ({"first_frame": np.vstack([FIRST[:3], [1e12, 0, 0]])}, "first_frame[3]: [1000000000000.0, 0.0, 0.0] is not a"),
        ({"first_frame": np.vstack([FIRST[:3], [np.inf, 0, 0]])}, "first_frame[3]: [inf, 0.0, 0.0] is not a finite"),
        ({"first_frame": FIRST + 500.0}, "4 of 4 labeled markers have no point of frame 0 within half their spacing"),
        ({"first_frame": FIRST * 1000.0}, "labeled markers have no point of frame 0"),
    ],
)
def test_a_bad_capture_is_refused_in_one_line(change: dict, message: str) -> None:
    fields = {"names": NAMES, "first_frame": FIRST, "rate": 100.0, "points": _frames()} | change
    with pytest.raises(InputError) as refused:
        Capture(**fields)
    assert message in str(refused.value) and "\n" not in str(refused.value)


def test_a_first_frame_near_frame_0_s_points_is_taken() -> None:
    """Noise and one marker whose point frame 0 lacks are a take's own, not a mistake."""
    frames = _frames()
    frames[0] = frames[0][:3] + 3.0
    Capture(NAMES, FIRST, rate=100.0, points=frames)


def test_a_capture_without_names_is_refused_when_labeled() -> None:
    """It failed in scipy's cKDTree (zero-size array); unnamed, a capture is what a model names."""
    unnamed = Capture([], np.zeros((0, 3)), rate=100.0, points=_frames(), unnamed_markers=4)
    with pytest.raises(InputError, match="needs at least one named marker"):
        CaptureLabeling(unnamed)


def test_frames_as_lists_label_as_arrays_do() -> None:
    frames = _frames()
    frames[3] = frames[3][[2, 0, 3, 1]]  # the points of a frame come unordered
    as_arrays, _ = CaptureLabeling(Capture(NAMES, FIRST, 100.0, points=frames)).label()
    as_lists, _ = CaptureLabeling(Capture(NAMES, FIRST.tolist(), 100, points=[f.tolist() for f in frames])).label()
    assert np.array_equal(as_lists.point_index, as_arrays.point_index)
    assert as_arrays.point_index[3].tolist() == [1, 3, 0, 2]


def test_an_empty_frame_may_be_an_empty_list() -> None:
    frames: list = _frames()
    frames[2] = []
    labels, _ = CaptureLabeling(Capture(NAMES, FIRST, 100.0, points=frames)).label()
    assert labels.occluded[2].all() and not labels.occluded[3].any()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"window": 1}, "window must be a whole number of at least 2"),
        ({"window": 10.5}, "window must be a whole number"),
        ({"window": "10"}, "window must be a whole number"),
        ({"formulation": 3}, "formulation must be a name, a table or a Formulation"),
        ({"association": "bogus"}, "association must be one of joint-3d, per-camera"),
        ({"layout_weight": -1.0}, "layout_weight must be a finite number of at least 0"),
        ({"layout_weight": float("nan")}, "layout_weight must be a finite number"),
        ({"layout_weight": "0.5"}, "layout_weight must be a finite number"),
        ({"best_view_switch_cost": float("inf")}, "best_view_switch_cost must be a finite number"),
        ({"second_pass": "no"}, "second_pass must be True or False"),
        ({"formulation": "simplex"}, "unknown formulation 'simplex'"),
        ({"formulation": {"name": "mht", "hypotheses": 101}}, "mht: parameter 'hypotheses' must be <= 100, got 101"),
        ({"formulation": {"name": "lp-l1", "decompose": "true"}}, "parameter 'decompose' must be true or false"),
    ],
)
def test_bad_labeling_options_are_refused_in_one_line(change: dict, message: str) -> None:
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        LabelingOptions(**change)


def _camera(name: str) -> Camera:
    return Camera(K=np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]]), distortion=np.zeros(4), R=np.eye(3),
                  t=np.array([0.0, 0, 2000]), image_size=(640, 480), name=name)


@pytest.mark.parametrize(
    ("cameras", "detections", "message"),
    [
        (["c1"], [[np.zeros((1, 2))]] * 3, "camera mode needs at least 2 calibrated cameras"),
        (["c1", "c2"], [[np.zeros((1, 2))]] * 3, "detections[0] must hold one (D, 2) array per camera (2 cameras)"),
        (["c1", "c2"], [[np.zeros((1, 2)), np.full((1, 2), 700.0)]] * 3, "is outside its 640x480 image"),
        (["c1", "c2"], [[np.zeros((2, 1)), np.zeros((1, 2))]] * 3, "detections[0][0]: points must be (D, 2)"),
        (["c1", "c2"], [[np.zeros((1, 2)), np.ones((1, 2))], [np.array([[5.0, 6], [7, 8], [5, 6]]), np.ones((1, 2))]] * 2,
         "detections[1] of camera 'c1': detections 0 and 2 are the same pixel (each listed twice by the export?)"),
        (["cam", "cam", "c3"], [[np.zeros((1, 2))] * 3] * 3, "camera names must be unique (outputs name views by them): 'cam'"),
    ],
)
def test_bad_camera_detections_are_refused_in_one_line(cameras: list, detections: list, message: str) -> None:
    with pytest.raises(InputError) as refused:
        Capture(NAMES, FIRST, 100.0, cameras=[_camera(c) for c in cameras], detections=detections)
    assert message in str(refused.value)
