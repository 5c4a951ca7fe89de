"""Captures the service once accepted and then mislabeled or failed to render are refused at
submission with a one-line 422, over real HTTP, in both routes; and the CLI refuses them too."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from capture_fixtures import camera_capture
from service_fixtures import REPO, serving
from test_service_security import JSON, small_document

from service.capture.capture import LabelingOptions
from service.capture.document import CaptureDocument
from service.io.recording import LabeledTrajectories
from service.server.results import trajectories_to_bytes
from service.server.settings import Settings
from service.server.store import store_for


@pytest.fixture(scope="module")
def db(tmp_path_factory) -> str:
    return f"sqlite:///{tmp_path_factory.mktemp('validation') / 'jobs.db'}"


@pytest.fixture(scope="module")
def client(db):
    with serving(Settings(db=db)) as client:
        yield client


@pytest.fixture(scope="module")
def cameras_document() -> dict:
    """Four calibrated cameras seeing six markers for four frames."""
    capture = camera_capture(frames=4, markers=6)
    return json.loads(CaptureDocument.of(capture, LabelingOptions(window=4)).model_dump_json())


def _refused(client, document: dict) -> list[str]:
    """The one-line 422 message of both routes (asserting they agree)."""
    messages = []
    for route in ("/v1/jobs", "/v1/solve"):
        answer = client.post(route, content=json.dumps(document), headers=JSON)
        assert answer.status_code == 422, (route, answer.text)
        messages.append(answer.json()["message"])
        assert "\n" not in messages[-1]
    assert messages[0] == messages[1]
    return messages


def _with_name(name: str) -> dict:
    document = small_document()
    document["markers"][1] = name
    return document


@pytest.mark.parametrize("name, problem", [
    ("", "is blank"), ("   ", "is blank"), (" M1", "starts or ends with whitespace"),
    ("M1\x1f", "starts or ends with whitespace"), ("M\x001", "control character"),
    ("M" * 256, "longer than 255 bytes"), ("é" * 128, "longer than 255 bytes"),
])
def test_a_marker_name_no_result_file_can_hold_is_refused(client, name, problem):
    [message, _] = _refused(client, _with_name(name))
    assert message.startswith("markers.1: marker name ") and problem in message


def test_names_a_c3d_holds_are_accepted(client):
    for name in ("M x", "M\u00e9", "M" * 255):
        assert client.post("/v1/jobs", content=json.dumps(_with_name(name)), headers=JSON).status_code == 202


@pytest.mark.parametrize("rate, problem", [(1e308, "less than or equal to 100000"), (100_000.5, "less than or equal"),
                                           (0, "greater than 0"), (1e-300, "greater than or equal to 0.001 (Hz)")])
def test_a_rate_outside_what_a_camera_records_is_refused(client, rate, problem):
    [message, _] = _refused(client, {**small_document(), "rate": rate})
    assert message.startswith("rate: ") and problem in message


def test_the_rates_at_the_bounds_are_accepted(client):
    for rate in (0.001, 100_000):
        assert client.post("/v1/jobs", content=json.dumps({**small_document(), "rate": rate}), headers=JSON).status_code == 202


def test_a_camera_capture_needs_two_cameras_with_detections(client, cameras_document):
    first = cameras_document["cameras"][0]["name"]
    one = {**cameras_document, "cameras": cameras_document["cameras"][:1],
           "detections": {first: cameras_document["detections"][first]}}
    [message, _] = _refused(client, one)
    assert message == f"detections: triangulation needs at least 2 cameras with detections; got 1 ({first})"
    # Cameras without detections see nothing (the module docstring), so they do not count.
    silent = {**cameras_document, "detections": {first: cameras_document["detections"][first]}}
    assert _refused(client, silent)[0] == message
    empty = {**cameras_document, "detections": {name: [[] for _ in frames] if name != first else frames
                                                for name, frames in cameras_document["detections"].items()}}
    assert _refused(client, empty)[0] == message
    assert client.post("/v1/solve", content=json.dumps(cameras_document), headers=JSON).status_code == 200


def test_the_cli_refuses_what_the_service_refuses(tmp_path, cameras_document):
    first = cameras_document["cameras"][0]["name"]
    for document in (_with_name(""), {**small_document(), "rate": 1e308},
                     {**cameras_document, "detections": {first: cameras_document["detections"][first]}}):
        capture = tmp_path / "capture.json"
        capture.write_text(json.dumps(document))
        run = subprocess.run([sys.executable, "-m", "service.cli", "-q", "track", str(capture), "--out",
                              str(tmp_path / "out.csv")], cwd=REPO, capture_output=True, text=True, timeout=120)
        assert run.returncode != 0 and "capture.json: " in run.stderr, run.stderr
        assert not (tmp_path / "out.csv").exists()


def test_a_result_that_cannot_be_written_names_no_temp_path(client, db):
    """A result stored before names were checked: the 422 says what is wrong, not where the server wrote it."""
    store = store_for(db)
    job, _ = store.add("local", "json", json.dumps(_with_name("")).encode(), 1)
    assert store.start(job.id)
    names = ["M0", "", "M2"]
    traj = LabeledTrajectories(names=names, positions=np.zeros((2, 3, 3)), occluded=np.zeros((2, 3), bool), rate=100.0)
    assert store.finish(job.id, trajectories_to_bytes(traj))
    answer = client.get(f"/v1/jobs/{job.id}/result", params={"format": "c3d"})
    assert answer.status_code == 422
    assert answer.json()["message"] == "result.c3d: C3D point 2 of 3 has a blank label"
