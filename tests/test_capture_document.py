"""The capture JSON document: exact round trip, and one-line errors naming the field."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from capture_fixtures import camera_capture, points_capture

from service.capture.capture import LabelingOptions
from service.capture.document import CaptureDocument, read_capture_document
from service.errors import InputError


@pytest.fixture(scope="module")
def camera_document() -> dict:
    return json.loads(CaptureDocument.of(camera_capture(frames=6, markers=8)).model_dump_json())


def test_camera_capture_round_trips_through_json():
    capture = camera_capture(frames=6, markers=8)
    text = CaptureDocument.of(capture, LabelingOptions("ilp", 7)).model_dump_json()
    document = read_capture_document(text, "capture.json")
    back = document.capture()
    assert back.names == capture.names and back.rate == capture.rate and back.mode == "cameras"
    assert np.array_equal(back.first_frame, capture.first_frame)
    assert [c.name for c in back.cameras] == [c.name for c in capture.cameras]
    assert all(a == b for a, b in zip(back.cameras, capture.cameras))
    for frame, expected in zip(back.detections, capture.detections):
        assert all(np.array_equal(a, b) for a, b in zip(frame, expected))
    assert document.options() == LabelingOptions("ilp", 7, "joint-3d")


def test_points_in_metres_are_read_in_millimetres():
    capture = points_capture(frames=3)
    document = json.loads(CaptureDocument.of(capture).model_dump_json())
    document["units"] = "m"
    document["first_frame"] = (np.asarray(document["first_frame"]) / 1000).tolist()
    document["points"] = [(np.asarray(frame) / 1000).tolist() for frame in document["points"]]
    back = read_capture_document(json.dumps(document), "m.json").capture()
    assert np.allclose(back.first_frame, capture.first_frame)
    assert all(np.allclose(a, b) for a, b in zip(back.points, capture.points))


def test_unnamed_markers_round_trip_and_must_not_be_negative():
    capture = points_capture(frames=3)
    capture.unnamed_markers = 2
    document = json.loads(CaptureDocument.of(capture).model_dump_json())
    assert read_capture_document(json.dumps(document), "u.json").capture().unnamed_markers == 2
    document["unnamed_markers"] = -1
    with pytest.raises(InputError, match="unnamed_markers"):
        read_capture_document(json.dumps(document), "u.json")


def _outside(d: dict) -> None:
    d["detections"][d["cameras"][1]["name"]][2].append([1e5, 10.0])


def _unknown_camera(d: dict) -> None:
    d["detections"]["cam-x"] = [[] for _ in range(6)]


def _short_camera(d: dict) -> None:
    d["detections"][d["cameras"][0]["name"]].pop()


def _singular_k(d: dict) -> None:
    d["cameras"][2]["K"] = [[0, 0, 0], [0, 0, 0], [0, 0, 1]]


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (_outside, r"detections\.\w+\.2\.\d+: \(100000, 10\) is outside the \d+x\d+ image"),
        (_unknown_camera, r"detections\.cam-x: camera 'cam-x' is not in cameras"),
        (_short_camera, r"detections: cameras have different frame counts \(\w+: 5, \w+: 6"),
        (_singular_k, r"cameras\.2: camera '\w+': K is singular"),
        (lambda d: d["first_frame"].pop(), r"first_frame has 7 rows for 8 markers"),
        (lambda d: d.update(window=1), r"window: Input should be greater than or equal to 2"),
        (lambda d: d.update(points=[[[0, 0, 0]]] * 6), r"give exactly one of points .* or detections"),
        (lambda d: d["cameras"][0].update(rvec=[0, 0, 0]), r"cameras\.0: give the world -> camera rotation as exactly one"),
        (lambda d: d.update(association="nearest"), r"association: Input should be 'joint-3d' or 'per-camera'"),
        (lambda d: d["markers"].append(d["markers"][0]), r"^bad.json: markers: marker name .* appears twice$"),
        (lambda d: d.update(rate=-1), r"rate: Input should be greater than 0"),
        (lambda d: d.update(colour="red"), r"colour: Extra inputs are not permitted"),
        (lambda d: d["first_frame"][0].__setitem__(0, -1e300),
         r"first_frame\.0\.0: Input should be greater than or equal to -1000000000"),
    ],
)
def test_bad_documents_name_the_field(camera_document: dict, mutate, message: str):
    read_capture_document(json.dumps(camera_document), "ok.json")  # the unmutated document is valid
    document = copy.deepcopy(camera_document)
    mutate(document)
    with pytest.raises(InputError, match=message) as caught:
        read_capture_document(json.dumps(document), "bad.json")
    assert "\n" not in str(caught.value) and str(caught.value).startswith("bad.json: ")


def test_malformed_json_is_one_line():
    with pytest.raises(InputError, match=r"^x\.json: Invalid JSON") as caught:
        read_capture_document(b'{"rate": 120,', "x.json")
    assert "\n" not in str(caught.value)


def test_a_camera_given_no_frames_sees_nothing_as_one_left_out_does(camera_document: dict):
    """``"cam": []`` was refused as a frame-count mismatch (cam: 0) though a camera left out is fine."""
    blind = camera_document["cameras"][0]["name"]
    empty, left_out = copy.deepcopy(camera_document), copy.deepcopy(camera_document)
    empty["detections"][blind] = []
    del left_out["detections"][blind]
    as_empty = read_capture_document(json.dumps(empty), "doc").capture()
    as_left_out = read_capture_document(json.dumps(left_out), "doc").capture()
    assert all(len(frame[0]) == 0 for frame in as_empty.detections)
    assert all(np.array_equal(a, b) for fa, fb in zip(as_empty.detections, as_left_out.detections) for a, b in zip(fa, fb))


def test_detections_with_a_confidence_say_to_leave_it_out(camera_document: dict):
    document = copy.deepcopy(camera_document)
    name = document["cameras"][0]["name"]
    document["detections"][name] = [[[u, v, 0.9] for u, v in frame] for frame in document["detections"][name]]
    said = r"detections\.\w+\.0\.0: .* \(a detection is \[u, v\] pixels: leave its confidence out\)"
    with pytest.raises(InputError, match=said):
        read_capture_document(json.dumps(document), "doc")
