"""Query filters are checked, and a bug answers a one-line 500 without dropping the connection;
a job whose window raises fails with a one-line error and keeps its earlier windows."""

from __future__ import annotations

import json
import socket
from urllib.parse import urlsplit

import numpy as np
import pytest
from service_fixtures import nan_array, serving, wait_for
from test_service_security import JSON, small_document

import service.server.routes_solve as routes_solve
import service.server.runner as runner
from service.labeling.capture_labeling import CaptureLabeling
from service.server.settings import Settings
from service.server.store import store_for

BUG = "index 1 is out of bounds for axis 1 with size 1\nsecond line"


@pytest.fixture(scope="module")
def db(tmp_path_factory) -> str:
    return f"sqlite:///{tmp_path_factory.mktemp('routes') / 'jobs.db'}"


@pytest.fixture(scope="module")
def client(db):
    with serving(Settings(db=db)) as client:
        yield client


def test_jobs_are_filtered_by_state_and_a_bogus_state_is_refused(client):
    job = client.post("/v1/jobs", content=json.dumps(small_document()), headers=JSON).json()
    assert wait_for(client, job["id"])["state"] == "done"
    done = client.get("/v1/jobs", params={"state": "done"}).json()
    assert job["id"] in [j["id"] for j in done["jobs"]] and {j["state"] for j in done["jobs"]} == {"done"}
    assert done["total"] == len(done["jobs"])
    assert client.get("/v1/jobs", params={"state": "failed"}).json()["jobs"] == []
    answer = client.get("/v1/jobs", params={"state": "bogus"})
    assert answer.status_code == 422
    assert answer.json()["message"] == (
        "query.state: Input should be 'queued', 'running', 'done', 'failed' or 'cancelled'")


class _Broken(CaptureLabeling):
    """A labeling with a bug: the window after the first raises."""

    def label(self, *args, **kwargs):
        raise IndexError(BUG)

    def windows(self, *args, **kwargs):
        for index, outcome in enumerate(super().windows(*args, **kwargs)):
            if index == 1:
                raise IndexError(BUG)
            yield outcome


def _raw_exchange(url: str, requests: list[bytes]) -> list[bytes]:
    """Each request sent on one keep-alive connection after the answer to the one before."""
    parts = urlsplit(url)
    answers = []
    with socket.create_connection((parts.hostname, parts.port), timeout=30) as connection:
        for request in requests:
            connection.sendall(request)
            answers.append(_read_answer(connection))
    return answers


def _read_answer(connection: socket.socket) -> bytes:
    data = b""
    while b"\r\n\r\n" not in data:
        data += connection.recv(65536) or _closed()
    head, body = data.split(b"\r\n\r\n", 1)
    length = next(int(line.split(b":")[1]) for line in head.split(b"\r\n") if line.lower().startswith(b"content-length"))
    while len(body) < length:
        body += connection.recv(65536) or _closed()
    return head + b"\r\n\r\n" + body


def _closed() -> bytes:
    raise AssertionError("the server closed the connection")


def test_a_bug_in_solve_is_a_one_line_500_and_the_connection_stays_open(client, monkeypatch):
    monkeypatch.setattr(routes_solve, "CaptureLabeling", _Broken)
    answer = client.post("/v1/solve", content=json.dumps(small_document()), headers=JSON)
    assert answer.status_code == 500
    assert answer.json() == {"message": "internal error; the server log has the details"}
    body = json.dumps(small_document()).encode()
    solve = (b"POST /v1/solve HTTP/1.1\r\nHost: test\r\nContent-Type: application/json\r\n"
             b"Content-Length: %d\r\n\r\n%s" % (len(body), body))
    health = b"GET /healthz HTTP/1.1\r\nHost: test\r\n\r\n"
    bug, after = _raw_exchange(str(client.base_url), [solve, health])
    assert bug.startswith(b"HTTP/1.1 500 ") and b"Traceback" not in bug
    assert after.startswith(b"HTTP/1.1 200 ")


def test_a_job_whose_window_raises_keeps_its_earlier_windows(client, db, monkeypatch):
    """The job runs here (``run_job`` is what a worker process runs), so the bug can be planted."""
    monkeypatch.setattr(runner, "CaptureLabeling", _Broken)
    document = {**small_document(frames=7), "window": 3}  # three windows
    store = store_for(db)
    job, _ = store.add("local", "json", json.dumps(document).encode(), 3)
    assert runner.run_job(db, job.id) == "failed"
    status = client.get(f"/v1/jobs/{job.id}").json()
    assert status["error"] == "window 1: internal error: IndexError: index 1 is out of bounds for axis 1 with size 1"
    assert status["windows_done"] == 1 and len(status["windows"]) == 1
    partial = client.get(f"/v1/jobs/{job.id}/result", params={"partial": "true"})
    assert partial.status_code == 200
    positions = nan_array(partial.json()["positions"])
    assert not np.isnan(positions[:3]).any()  # frame 0 and window 0's frames 1-2
    assert np.isnan(positions[3:]).all()  # no stored window labeled these


def test_a_job_stored_before_its_input_was_refused_fails_saying_why(client, db):
    """An input accepted by an older markerflow and refused now: a one-line failure and a 422, not a bug."""
    document = small_document()
    document["markers"][1] = ""
    job, _ = store_for(db).add("local", "json", json.dumps(document).encode(), 1)
    assert runner.run_job(db, job.id) == "failed"
    assert client.get(f"/v1/jobs/{job.id}").json()["error"] == "input: markers.1: marker name '' is blank"
    partial = client.get(f"/v1/jobs/{job.id}/result", params={"partial": "true"})
    assert (partial.status_code, partial.json()) == (422, {"message": "input: markers.1: marker name '' is blank"})
