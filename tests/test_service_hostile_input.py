"""Inputs that once answered 500 answer a one-line 4xx, and a JSON body over a limit is refused
from its bytes (``prescan``) with the message ``check_limits`` gives after parsing."""

from __future__ import annotations

import json
import time

import pytest
from service_fixtures import FUZZ_C3D, RELIABILITY, serving
from test_service_security import JSON, small_document

from service.capture.document import CaptureDocument
from service.errors import InputError
from service.server.limits import check_body_limits, check_limits
from service.server.prescan import MAX_DEPTH
from service.server.settings import Limits, Settings

LIMITS = Limits(max_frames=6, max_markers=4, max_points_per_frame=5, max_detections_per_camera=3, max_cameras=2)


@pytest.fixture(scope="module")
def client(store_url):
    """A server on SQLite and on PostgreSQL: a NUL byte or a 300-character filename once gave a 500 on PostgreSQL only."""
    with serving(Settings(db=store_url)) as client:
        yield client


def _upload(client, **fields) -> tuple[int, str]:
    answer = client.post("/v1/jobs", files={"file": ("take.c3d", FUZZ_C3D.read_bytes())}, data=fields)
    return answer.status_code, answer.json()["message"]


def test_the_issues_500s_are_one_line_4xx(client):
    assert _upload(client, window="²") == (422, "window: expected a whole number of frames, got '²'")
    assert _upload(client, window="9" * 5000)[0] == 422
    deep = (RELIABILITY / "deep_formulation.json").read_text()
    assert _upload(client, formulation=deep) == (422, f"formulation: nested deeper than {MAX_DEPTH} levels")
    answer = client.post("/v1/jobs", files={"file": ("badlabel.c3d", (RELIABILITY / "badlabel.c3d").read_bytes())})
    assert answer.status_code == 422 and "\n" not in answer.json()["message"]
    assert answer.json()["message"].startswith("file: badlabel.c3d: C3D point 16 of 39 has a label that is not UTF-8")
    body = '{"rate": 100, "markers": ' + "[" * 10_000 + "]" * 10_000 + "}"
    assert client.post("/v1/jobs", content=body, headers=JSON).json() == {
        "message": f"body: nested deeper than {MAX_DEPTH} levels"}
    assert client.get("/v1/jobs/abc%00def").status_code == 404
    long_name = "x" * 300 + ".c3d"
    answer = client.post("/v1/jobs", files={"file": (long_name, FUZZ_C3D.read_bytes())}, data={"window": "50"})
    assert answer.status_code == 202 and answer.json()["source"] == long_name[:300]


def test_a_window_past_the_limit_is_refused_on_either_path(client):
    """580 frames a window held a job slot in its first window for minutes; no limit bounded it."""
    assert _upload(client, window="251") == (422, "window: 251 frames exceeds the limit of 250 (limits.max_window)")
    document = {**small_document(), "window": 10**30}
    answer = client.post("/v1/jobs", content=json.dumps(document), headers=JSON)
    assert answer.status_code == 422 and answer.json()["message"].startswith("window: 10000000000000000000000000000")


def _limit_messages(document: dict) -> tuple[str | None, str | None]:
    """(refused from the bytes, refused after parsing): the messages, or None where accepted."""
    body = json.dumps(document).encode()
    answers: list[str | None] = []
    for check in (lambda: check_body_limits(body, LIMITS),
                  lambda: check_limits(CaptureDocument.model_construct(**json.loads(body)), LIMITS)):
        try:
            check()
            answers.append(None)
        except InputError as error:
            answers.append(str(error))
    return answers[0], answers[1]


def _detections(cameras: int, frames: int, per_frame: list[int]) -> dict:
    """Detections of each camera per frame; ``per_frame[c * frames + f]`` points in camera c, frame f."""
    names = [f'cam "{c}" [{c}]' for c in range(cameras)]  # quotes and brackets inside a key
    return {"markers": ["a", "b"], "detections": {
        name: [[[1.0 + k, 2.0] for k in range(per_frame[c * frames + f])] for f in range(frames)]
        for c, name in enumerate(names)}, "cameras": [{"name": name} for name in names]}


@pytest.mark.parametrize("document", [
    small_document(frames=7), small_document(frames=6), small_document(markers=5),
    {**small_document(frames=3, points=6), "markers": ["a,]b", 'c\\"[', "d", "e"]},
    small_document(markers=2, frames=4, points=5),
    _detections(2, 3, [1, 2, 3, 2, 4, 1]), _detections(2, 3, [1, 1, 1, 1, 1, 1]), _detections(3, 1, [1, 1, 1]),
    _detections(1, 7, [1] * 7),
])
def test_the_byte_counts_give_the_parsed_counts_message(document):
    scanned, parsed = _limit_messages(document)
    assert scanned == parsed


def test_a_large_body_over_the_points_limit_is_refused_fast():
    frames = [[[float(p), 0.0, 1000.0] for p in range(3)]] * 150_000 + [[[1.0, 2.0, 3.0]] * 2001]
    body = json.dumps({"rate": 100, "markers": ["A", "B", "C"], "points": frames}).encode()
    assert len(body) > 2**23  # more than one scan chunk
    started = time.perf_counter()
    with pytest.raises(InputError, match=r"^points.150000: 2001 points exceeds the limit of 2000"):
        check_body_limits(body, Limits(max_frames=200_000))
    assert time.perf_counter() - started < 2.0
