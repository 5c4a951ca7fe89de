"""The capture JSON takes what it says and nothing that would be read as something else:
``"rate": true`` was labeled at 1 Hz, ``"unnamed_markers": 1000000`` with 41 points a frame
was accepted, a marker named ``*0`` vanished from the C3D read back (readers take ``*N`` for
an unlabeled trajectory), and a UTF-8 byte-order mark was "Invalid JSON ... line 1 column 1"."""

from __future__ import annotations

import json
import re
from collections.abc import Callable

import pytest
from capture_fixtures import camera_capture, points_capture

from service.capture.document import CaptureDocument, read_capture_document
from service.errors import InputError


def _points_document() -> dict:
    return json.loads(CaptureDocument.of(points_capture(frames=3)).model_dump_json())


def _camera_document() -> dict:
    return json.loads(CaptureDocument.of(camera_capture(frames=3, markers=4)).model_dump_json())


def _set(key: str, value: object) -> Callable[[dict], None]:
    return lambda d: d.__setitem__(key, value)


@pytest.mark.parametrize(("mutate", "where"), [
    (_set("rate", True), "rate: Input should be a number, not true"),
    (_set("window", True), "window: Input should be a number, not true"),
    (_set("unnamed_markers", True), "unnamed_markers: Input should be a number, not true"),
    (lambda d: d["first_frame"][0].__setitem__(0, False), "first_frame.0.0: Input should be a number, not false"),
    (lambda d: d["points"][1][0].__setitem__(2, True), "points.1.0.2: Input should be a number, not true"),
    # lax parsing read "120" as 120 Hz and "no" or 0 as no second pass; the README says numbers are JSON numbers
    (_set("rate", "120"), "rate: Input should be a number, not a string ('120')"),
    (_set("window", "20"), "window: Input should be a number, not a string ('20')"),
    (lambda d: d["points"][1][0].__setitem__(2, "3"), "points.1.0.2: Input should be a number, not a string ('3')"),
    (_set("second_pass", "no"), "second_pass: Input should be a valid boolean"),
    (_set("second_pass", 0), "second_pass: Input should be a valid boolean"),
    # Python's JSON reads NaN and Infinity; they were refused as "greater than or equal to -1e9"
    (lambda d: d["points"][1][0].__setitem__(2, float("nan")), "points.1.0.2: Input should be a finite number, not nan"),
    (lambda d: d["first_frame"][0].__setitem__(0, float("-inf")),
     "first_frame.0.0: Input should be a finite number, not -inf"),
])
def test_a_boolean_a_string_or_nan_is_not_a_number(mutate: Callable[[dict], None], where: str) -> None:
    document = _points_document()
    mutate(document)
    with pytest.raises(InputError, match=f"^b.json: {re.escape(where)}"):
        read_capture_document(json.dumps(document), "b.json")


def test_a_boolean_image_size_is_not_a_number() -> None:
    document = _camera_document()
    document["cameras"][0]["image_size"][0] = True
    with pytest.raises(InputError, match=r"cameras.0.image_size.0: Input should be a number, not true"):
        read_capture_document(json.dumps(document), "b.json")


def test_unnamed_markers_cannot_outnumber_the_points_of_every_frame() -> None:
    document = _points_document()
    most = max(len(frame) for frame in document["points"])
    document["unnamed_markers"] = most
    assert read_capture_document(json.dumps(document), "u.json").unnamed_markers == most
    document["unnamed_markers"] = most + 1
    with pytest.raises(InputError, match=f"^u.json: unnamed_markers: {most + 1} unnamed markers, but no frame of "
                                         f"points holds more than {most} points$"):
        read_capture_document(json.dumps(document), "u.json")


@pytest.mark.parametrize("name", ["*0", "*12"])
def test_a_marker_named_as_an_unlabeled_trajectory_is_refused(name: str) -> None:
    document = _points_document()
    document["markers"][1] = name
    with pytest.raises(InputError, match=r"markers.1: marker name '\*\d+' is how a C3D names an unlabeled"):
        read_capture_document(json.dumps(document), "s.json")


@pytest.mark.parametrize("name", ["*", "*a", "a*0", "*0x"])
def test_names_merely_with_a_star_are_markers(name: str) -> None:
    document = _points_document()
    document["markers"][1] = name
    assert read_capture_document(json.dumps(document), "s.json").markers[1] == name


def test_a_byte_order_mark_is_skipped() -> None:
    document = _points_document()
    text = json.dumps(document)
    assert read_capture_document(text.encode("utf-8-sig"), "bom.json").markers == document["markers"]
    assert read_capture_document("\ufeff" + text, "bom.json").markers == document["markers"]


@pytest.mark.parametrize("encoding", ["latin-1", "utf-16"])
def test_a_document_not_in_utf8_says_so(encoding: str) -> None:
    document = _points_document()
    document["markers"][0] = "épaule"
    with pytest.raises(InputError, match=r"^c.json: not UTF-8 text \(byte \d+ is 0x[0-9a-f]{2}\); save it as UTF-8$"):
        read_capture_document(json.dumps(document, ensure_ascii=False).encode(encoding), "c.json")


def test_a_detection_listed_twice_in_a_frame_is_refused() -> None:
    """Every centroid exported twice: per-camera fused two markers onto one position, and the
    warning blamed copied columns."""
    document = _camera_document()
    camera = document["cameras"][1]["name"]
    frame = document["detections"][camera][2]
    frame.append(list(frame[0]))
    with pytest.raises(InputError, match=rf"^d.json: detections.{camera}.2: detections 0 and {len(frame) - 1} are the "
                                         r"same pixel \(each listed twice by the export\?\)$"):
        read_capture_document(json.dumps(document), "d.json")
