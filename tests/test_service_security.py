"""Tokens keep callers apart; limits and bad input answer 4xx naming the field and the limit."""

from __future__ import annotations

import json
import socket
import subprocess
import sys

import httpx
import pytest
from capture_fixtures import camera_capture
from service_fixtures import REPO, document_json, serving, wait_for

from service.capture.capture import Capture
from service.errors import InputError
from service.server.app import create_app
from service.server.settings import Limits, Settings

ALICE, BOB = "alice-secret-0123456789", "bob-secret-0123456789"
JSON = {"content-type": "application/json"}


def small_document(markers: int = 3, frames: int = 4, points: int | None = None) -> dict:
    """Markers on a line 100 mm apart, drifting 1 mm a frame; ``points`` per frame (default: one per marker)."""
    first = [[100.0 * m, 0.0, 1000.0] for m in range(markers)]
    per_frame = markers if points is None else points
    frames_points = [[[100.0 * p + f, 0.0, 1000.0] for p in range(per_frame)] for f in range(frames)]
    return {"rate": 100, "markers": [f"M{m}" for m in range(markers)], "first_frame": first, "points": frames_points}


@pytest.fixture(scope="module")
def guarded(store_url):
    """A server with two tokens, on SQLite and on PostgreSQL."""
    with serving(Settings(db=store_url, tokens={"alice": ALICE, "bob": BOB})) as client:
        yield client


def as_(token: str | None) -> dict:
    return {"Authorization": f"Bearer {token}"} if token else {}


def test_missing_or_unknown_token_is_401(guarded):
    for headers in ({}, as_("not-a-token-at-all"), {"Authorization": "Basic YWxpY2U6eA=="}):
        answer = guarded.get("/v1/jobs", headers=headers)
        assert answer.status_code == 401 and answer.headers["www-authenticate"] == "Bearer"
        posted = guarded.post("/v1/jobs", content=json.dumps(small_document()), headers={**JSON, **headers})
        assert posted.status_code == 401


def test_a_token_sees_and_cancels_only_its_own_jobs(guarded):
    accepted = guarded.post("/v1/jobs", content=json.dumps(small_document()), headers={**JSON, **as_(ALICE)})
    assert accepted.status_code == 202
    job_id = accepted.json()["id"]
    guarded.headers.update(as_(ALICE))
    assert wait_for(guarded, job_id)["state"] == "done"
    for path in (f"/v1/jobs/{job_id}", f"/v1/jobs/{job_id}/result", f"/v1/jobs/{job_id}/events"):
        assert guarded.get(path, headers=as_(BOB)).status_code == 404
        assert guarded.get(path, headers=as_(ALICE)).status_code == 200
    assert guarded.delete(f"/v1/jobs/{job_id}", headers=as_(BOB)).status_code == 404
    assert job_id not in [j["id"] for j in guarded.get("/v1/jobs", headers=as_(BOB)).json()["jobs"]]
    assert job_id in [j["id"] for j in guarded.get("/v1/jobs", headers=as_(ALICE)).json()["jobs"]]
    # The 404 for another's job reads exactly like the 404 for no job at all.
    assert guarded.get(f"/v1/jobs/{job_id}", headers=as_(BOB)).json() == {"message": f"no job {job_id}"}


def test_a_body_without_a_token_is_refused_before_it_is_read(guarded):
    """Headers declaring 50 MB and no body sent: the 401 comes at once, not after a read."""
    port = guarded.base_url.port
    with socket.create_connection(("127.0.0.1", port), timeout=5) as raw:
        raw.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                    b"Content-Length: 50000000\r\nAuthorization: Bearer not-a-token-at-all\r\n\r\n{")
        answer = b""
        while chunk := raw.recv(4096):  # the server closes the connection after its answer
            answer += chunk
    head = answer.decode()
    assert head.startswith("HTTP/1.1 401") and "www-authenticate: Bearer" in head and "unknown bearer token" in head


def test_metrics_need_a_token_and_name_no_owner(guarded):
    assert httpx.get(guarded.base_url.join("/metrics")).status_code == 401  # guarded may carry a token by now
    assert guarded.post("/v1/jobs", content=json.dumps(small_document()), headers={**JSON, **as_(BOB)}).status_code == 202
    text = guarded.get("/metrics", headers=as_(BOB)).text
    assert "markerflow_jobs{" in text and not any(name in text for name in ("alice", "bob", ALICE, BOB, "owner"))
    assert guarded.get("/healthz").json() == {"status": "ok"}


def test_api_docs_follow_the_setting(tmp_path):
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}", api_docs=False)) as client:
        assert [client.get(path).status_code for path in ("/docs", "/redoc", "/openapi.json")] == [404, 404, 404]
        assert client.get("/healthz").status_code == 200


def test_a_non_loopback_bind_without_tokens_refuses_to_start(tmp_path):
    with pytest.raises(InputError, match="refusing to serve on 0.0.0.0 without tokens"):
        create_app(Settings(host="0.0.0.0", db=f"sqlite:///{tmp_path / 'x.db'}"))
    done = subprocess.run([sys.executable, "-m", "service.cli", "serve", "--host", "0.0.0.0", "--port", "0",
                           "--db", f"sqlite:///{tmp_path / 'x.db'}"], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip().startswith("error: refusing to serve on 0.0.0.0 without tokens")
    assert len(done.stderr.strip().splitlines()) == 1


LIMITS = Limits(max_body_bytes=100_000, max_frames=50, max_markers=10, max_points_per_frame=30,
                max_detections_per_camera=20, max_cameras=3)


@pytest.fixture(scope="module")
def limited(tmp_path_factory):
    db = tmp_path_factory.mktemp("limits") / "jobs.db"
    with serving(Settings(db=f"sqlite:///{db}", limits=LIMITS)) as client:
        yield client


@pytest.fixture(scope="module")
def camera_document() -> dict:
    full = camera_capture(frames=6, markers=4)
    capture = Capture(full.names, full.first_frame, full.rate, cameras=full.cameras[:3],
                      detections=[frame[:3] for frame in full.detections])
    return json.loads(document_json(capture))


def test_a_body_over_the_limit_is_413_before_parsing(limited):
    big = b'{"rate": 100, "markers": ["' + b"x" * 200_000 + b'"]}'
    answer = limited.post("/v1/jobs", content=big, headers=JSON)
    assert answer.status_code == 413 and "(limits.max_body_bytes)" in answer.json()["message"]
    # Chunked, so no Content-Length to go by: the stream is cut at the limit.
    chunked = limited.post("/v1/jobs", content=(big[i:i + 10_000] for i in range(0, len(big), 10_000)), headers=JSON)
    assert chunked.status_code == 413 and "(limits.max_body_bytes)" in chunked.json()["message"]
    assert limited.post("/v1/solve", content=big, headers=JSON).status_code == 413


def _problem(client, document, status: int = 422, path: str = "/v1/jobs") -> str:
    body = document if isinstance(document, (str, bytes)) else json.dumps(document)
    answer = client.post(path, content=body, headers=JSON)
    assert answer.status_code == status, answer.text
    return answer.json()["message"]


def test_capture_dimensions_over_the_limits_name_field_and_limit(limited, camera_document):
    assert _problem(limited, small_document(frames=51)) == "frames: 51 frames exceeds the limit of 50 (limits.max_frames)"
    assert _problem(limited, small_document(markers=11)) == "markers: 11 markers exceeds the limit of 10 (limits.max_markers)"
    crowded = small_document()
    crowded["points"][2] += [[500.0 + k, 0.0, 1000.0] for k in range(28)]
    assert _problem(limited, crowded) == "points.2: 31 points exceeds the limit of 30 (limits.max_points_per_frame)"
    cameras = json.loads(json.dumps(camera_document))
    cameras["cameras"].append({**cameras["cameras"][0], "name": "extra"})
    assert _problem(limited, cameras) == "cameras: 4 cameras exceeds the limit of 3 (limits.max_cameras)"
    cluttered = json.loads(json.dumps(camera_document))
    name = cluttered["cameras"][1]["name"]
    cluttered["detections"][name][3] += [[10.0 + k, 10.0] for k in range(21)]
    count = len(cluttered["detections"][name][3])
    assert _problem(limited, cluttered) == (
        f"detections.{name}.3: {count} detections exceeds the limit of 20 (limits.max_detections_per_camera)")
    assert _problem(limited, small_document(frames=21), path="/v1/solve").startswith("frames: 21 frames is more than one window")


def test_bad_input_is_422_naming_the_field(limited, camera_document):
    assert _problem(limited, '{"rate": 100,').startswith("Invalid JSON")
    assert _problem(limited, {**small_document(), "rate": "fast"}) == "rate: Input should be a number, not a string ('fast')"
    assert _problem(limited, {**small_document(), "window": 1}).startswith("window: Input should be greater than or equal to 2")
    unknown = _problem(limited, {**small_document(), "formulation": "simplex"})
    assert unknown.startswith("formulation: unknown formulation 'simplex'")
    assert _problem(limited, {**small_document(), "formulation": {"name": "ilp", "time_limt": 3}}).startswith(
        "formulation: formulation 'ilp' has no parameter 'time_limt'")
    assert _problem(limited, {**small_document(), "formulation": {"name": "ilp", "decompose": "no"}}) == (
        "formulation.decompose: expected a bool, got 'no'")
    outside = json.loads(json.dumps(camera_document))
    name, (width, height) = outside["cameras"][1]["name"], outside["cameras"][1]["image_size"]
    outside["detections"][name][2].append([width + 50.0, 10.0])
    index = len(outside["detections"][name][2]) - 1
    assert _problem(limited, outside) == (
        f"detections.{name}.2.{index}: ({width + 50:g}, 10) is outside the {width}x{height} image")
    unknown = json.loads(json.dumps(camera_document))
    unknown["detections"]["nope"] = unknown["detections"][name]
    assert _problem(limited, unknown).startswith("detections.nope: camera 'nope' is not in cameras")
    assert _problem(limited, {**camera_document, "association": "magic"}).startswith("association: Input should be")
    assert limited.post("/v1/jobs", content="rate=100", headers={"content-type": "text/plain"}).status_code == 415
    assert limited.get("/v1/jobs", params={"limit": 0}).json()["message"].startswith("query.limit: Input should be greater")


def test_a_json_body_is_read_as_a_json_file_is(limited):
    """A byte-order mark (Windows editors write one) was "Invalid JSON ... line 1 column 1" over
    HTTP while `track` took the same file; a body not in UTF-8 now says so."""
    body = json.dumps(small_document()).encode()
    assert limited.post("/v1/jobs", content=b"\xef\xbb\xbf" + body, headers=JSON).status_code == 202
    latin = body.replace(b'"rate"', b'"rate", "markers\xe9": 1, "x"', 1)
    assert _problem(limited, latin).startswith("not UTF-8 text (byte ")


def test_bad_uploads_are_422_naming_the_file(limited, tmp_path):
    def upload(name: str, content: bytes, **data) -> str:
        answer = limited.post("/v1/jobs", files={"file": (name, content)}, data=data)
        assert answer.status_code == 422, answer.text
        return answer.json()["message"]

    assert upload("take.txt", b"hello") == "file: take.txt is not a .c3d, .trc or .csv file"
    assert upload("take.c3d", b"\x00" * 600).startswith("file: take.c3d: ")
    assert upload("take.trc", b"PathFileType\t4\n").startswith("file: take.trc: ")
    assert upload("take.c3d", b"", window="many") == "window: expected a whole number of frames, got 'many'"
    assert upload("take.c3d", b"", formulation="{not json").startswith("formulation: not a JSON object")
    answer = limited.post("/v1/jobs", files={"file": ("a.c3d", b"")}, data={"colour": "red"})
    assert answer.status_code == 422 and answer.json()["message"].startswith("colour: unknown form field")
    assert upload("t.c3d", b"x").startswith("file: t.c3d: ")  # a one-byte file is an answer, not a crash
    assert limited.get("/healthz").status_code == 200
