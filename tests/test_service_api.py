"""The service over real HTTP: jobs from JSON and from an uploaded C3D, in both input modes,
give exactly what the library gives; solve, events, listing, cancel, metrics. Certificates
are checked against windows solved by the formulations themselves."""

from __future__ import annotations

import asyncio
import json
import time

import ezc3d
import numpy as np
import pytest
from capture_fixtures import camera_capture
from service_fixtures import document_json, generated_capture, nan_array, serving, wait_for

from formulations.markers.cloud_candidates import CloudGating, cloud_candidates
from formulations.markers.state import MarkerState
from formulations.methods.registry import get_formulation
from formulations.window.build import build_window
from formulations.window.solution import WindowSolution
from service.capture.capture import Capture, LabelingOptions
from service.capture.from_recording import capture_from_recording
from service.evaluation.scene import generate_scene
from service.io.formats import read_labeled, write_labeled
from service.io.recording import Recording, is_unlabeled
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.cloud import MARKER_COSTS
from service.labeling.stats import WindowStats, finite_or_none
from service.server.events import job_events
from service.server.settings import Settings

OPTIONS = LabelingOptions(window=10)
JSON = {"content-type": "application/json"}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    db = tmp_path_factory.mktemp("service") / "jobs.db"
    with serving(Settings(db=f"sqlite:///{db}", max_parallel_jobs=2)) as client:
        yield client


@pytest.fixture(scope="module")
def capture() -> Capture:
    return generated_capture(frames=60, seed=3)


@pytest.fixture(scope="module")
def cluttered() -> Capture:
    """One 20-frame window in heavy clutter whose LP optimum is fractional (a nonzero gap)."""
    return generated_capture(frames=20, seed=38, noise_mm=10.0, ghosts_per_frame=100.0)


def _solved_directly(capture: Capture, formulation: str) -> WindowSolution:
    """A one-window capture solved by the formulations themselves, posed as the service poses 3D
    points: candidates gated from the labeled first frame, marker arc costs, no layout term."""
    state = MarkerState.from_first_frame(np.asarray(capture.first_frame, dtype=float))
    method = get_formulation(formulation)
    gating = CloudGating() if method.look_ahead else CloudGating(step_median_frames=0)  # as the service poses it
    gated = cloud_candidates(state, capture.points[1:], gating, None)
    return method.solve(build_window(gated.candidates, MARKER_COSTS)[0])


def _solve(client, capture: Capture, formulation: str) -> dict:
    """The window solved once, from the labeled first frame: no second pass (``_solved_directly``)."""
    options = LabelingOptions(formulation=formulation, window=capture.n_frames, second_pass=False)
    answer = client.post("/v1/solve", content=document_json(capture, options), headers=JSON)
    assert answer.status_code == 200, answer.text
    return answer.json()


def _assert_consistent(certificate: dict) -> None:
    """The figures agree: gap = max(0, cost - bound) / |cost|, and null exactly when no bound is proven."""
    if certificate["lower_bound"] is None:
        assert certificate["gap"] is None and not certificate["integral"]
        return
    cost, bound = certificate["cost"], certificate["lower_bound"]
    assert bound <= cost + 1e-9 * abs(cost)
    assert certificate["gap"] == pytest.approx(max(0.0, cost - bound) / abs(cost), rel=1e-9, abs=1e-15)


def _assert_same_certificates(windows: list[dict], stats: list[WindowStats]) -> None:
    """Each served window's certificate is the library's, with null for what nothing proved."""
    for window, s in zip(windows, stats, strict=True):
        assert (window["template"], window["last"], window["integral"], window["status"]) == (
            s.template, s.last, s.integral, s.status)
        assert (window["cost"], window["lower_bound"], window["gap"]) == (
            s.cost, finite_or_none(s.lower_bound), finite_or_none(s.gap))
        _assert_consistent(window)


def _submit(client, body: str) -> dict:
    answer = client.post("/v1/jobs", content=body, headers={"content-type": "application/json"})
    assert answer.status_code == 202, answer.text
    assert answer.headers["location"] == f"/v1/jobs/{answer.json()['id']}"
    return answer.json()


def _library_files(traj, folder, source=None):
    write_labeled(folder / "library.csv", traj, source)
    write_labeled(folder / "library.c3d", traj, source)
    return (folder / "library.csv").read_bytes(), read_labeled(folder / "library.c3d")


def _assert_same_result(client, job_id: str, expected, folder, source=None) -> None:
    """JSON bitwise, CSV byte for byte, C3D as read back: all equal to the library's output
    (written from ``source``, the uploaded file's, as ``markerflow track`` writes it)."""
    answer = client.get(f"/v1/jobs/{job_id}/result", params={"format": "json"})
    assert answer.status_code == 200 and answer.headers["content-type"] == "application/json"
    result = answer.json()
    assert result["markers"] == expected.names
    assert np.array_equal(nan_array(result["positions"]), expected.positions, equal_nan=True)
    assert np.array_equal(np.array(result["occluded"]), expected.occluded)
    assert np.array_equal(nan_array(result["filled"]), expected.filled, equal_nan=True)
    csv_bytes, c3d_recording = _library_files(expected, folder, source)
    answer = client.get(f"/v1/jobs/{job_id}/result", params={"format": "csv"})
    assert answer.headers["content-type"].startswith("text/csv")
    assert f'_labeled-{job_id[:8]}.csv"; filename*=' in answer.headers["content-disposition"]  # named after the take
    assert answer.content == csv_bytes
    answer = client.get(f"/v1/jobs/{job_id}/result", params={"format": "c3d"})
    assert answer.headers["content-disposition"].endswith(".c3d")
    (folder / "served.c3d").write_bytes(answer.content)
    served = read_labeled(folder / "served.c3d")
    assert served.names == c3d_recording.names
    assert [name for name in served.names if not is_unlabeled(name)] == expected.names  # then the ghosts, *N
    assert np.array_equal(served.positions, c3d_recording.positions, equal_nan=True)
    # Read back through ezc3d too: the labels and every visible sample, in mm.
    raw = ezc3d.c3d(str(folder / "served.c3d"))
    assert raw["parameters"]["POINT"]["LABELS"]["value"][: len(expected.names)] == expected.names
    seen = ~expected.occluded
    markers = raw["data"]["points"][:3, : len(expected.names)].transpose(2, 1, 0)
    assert np.allclose(markers[seen], expected.positions[seen], atol=1e-3)


def test_json_job_runs_to_done_and_matches_the_library(client, capture, tmp_path):
    accepted = _submit(client, document_json(capture, OPTIONS))
    assert accepted["state"] == "queued" and accepted["windows_total"] == 7
    job = wait_for(client, accepted["id"])
    assert job["state"] == "done", job
    assert job["windows_done"] == job["windows_total"] == len(job["windows"]) == 7
    assert [w["index"] for w in job["windows"]] == list(range(7))
    expected, stats = CaptureLabeling(capture, OPTIONS).label()
    assert [w["integral"] for w in job["windows"]] == [s.integral for s in stats]
    _assert_same_certificates(job["windows"], stats)
    _assert_same_result(client, accepted["id"], expected, tmp_path)


def test_uploaded_c3d_is_relabeled_like_the_library(client, tmp_path):
    truth = generate_scene(n_frames=40, seed=5)
    occluded = np.zeros(truth.positions.shape[:2], dtype=bool)
    occluded[10:14, 3] = True  # a gap in the file: those samples are dropped from the cloud
    write_labeled(tmp_path / "take.c3d", _as_labeled(truth, occluded))
    with (tmp_path / "take.c3d").open("rb") as upload:
        answer = client.post("/v1/jobs", files={"file": ("take.c3d", upload)}, data={"window": "8", "formulation": "ilp"})
    assert answer.status_code == 202, answer.text
    assert answer.json()["source"] == "take.c3d"
    job = wait_for(client, answer.json()["id"])
    assert job["state"] == "done", job
    options = LabelingOptions(formulation="ilp", window=8)
    expected, _ = CaptureLabeling(capture_from_recording(read_labeled(tmp_path / "take.c3d")), options).label()
    assert expected.occluded[10:14, 3].all()
    _assert_same_result(client, job["id"], expected, tmp_path, read_labeled(tmp_path / "take.c3d").source)


def _as_labeled(truth: Recording, occluded: np.ndarray):
    from service.io.recording import LabeledTrajectories

    positions = np.where(occluded[..., None], np.nan, truth.positions)
    return LabeledTrajectories(truth.names, positions, occluded, truth.rate)


def test_camera_mode_job_runs_to_done(client, tmp_path):
    full = camera_capture(frames=40, markers=6)
    capture = Capture(full.names, full.first_frame, full.rate, cameras=full.cameras[:3],
                      detections=[frame[:3] for frame in full.detections])
    accepted = _submit(client, document_json(capture, OPTIONS))
    job = wait_for(client, accepted["id"])
    assert job["state"] == "done", job
    expected, _ = CaptureLabeling(capture, OPTIONS).label()
    _assert_same_result(client, accepted["id"], expected, tmp_path)


def test_events_stream_every_window_then_the_final_state(client, capture):
    accepted = _submit(client, document_json(capture, OPTIONS))
    events = []
    with client.stream("GET", f"/v1/jobs/{accepted['id']}/events") as stream:
        assert stream.headers["content-type"].startswith("text/event-stream")
        for block in stream.iter_text():
            events.append(block)
    text = "".join(events)
    parsed = [(part.split("\n")[0].removeprefix("event: "), json.loads(part.split("\n")[1].removeprefix("data: ")))
              for part in text.strip().split("\n\n")]
    windows = [data for kind, data in parsed if kind == "window"]
    assert [w["windows_done"] for w in windows] == list(range(1, 8))
    assert all(w["windows_total"] == 7 and "integral" in w["window"] for w in windows)
    assert parsed[-1][0] == "state" and parsed[-1][1]["state"] == "done"


@pytest.mark.parametrize("formulation", ["lp-l1", "nn-hungarian"])
def test_job_status_certifies_a_window_as_solve_does(client, cluttered, formulation):
    options = LabelingOptions(formulation=formulation, window=cluttered.n_frames, second_pass=False)
    job = wait_for(client, _submit(client, document_json(cluttered, options))["id"])
    assert job["state"] == "done", job
    (window,) = job["windows"]
    solved = _solve(client, cluttered, formulation)["certificate"]
    figures = ("integral", "gap", "cost", "lower_bound", "status")
    assert {k: window[k] for k in figures} == {k: solved[k] for k in figures}
    assert window["cost"] == pytest.approx(_solved_directly(cluttered, formulation).cost, rel=1e-12)
    _, stats = CaptureLabeling(cluttered, options).label()
    _assert_same_certificates(job["windows"], stats)


def test_cancel_stops_a_running_job_between_windows(client):
    capture = generated_capture(frames=200, seed=6)
    slow = LabelingOptions(formulation={"name": "ilp", "lp_first": False}, window=4)
    accepted = _submit(client, document_json(capture, slow))
    running = wait_for(client, accepted["id"], states=("running",))
    assert running["state"] == "running"
    cancelled = client.delete(f"/v1/jobs/{accepted['id']}")
    assert cancelled.status_code == 200 and cancelled.json()["state"] == "cancelled"
    time.sleep(0.5)  # a window in flight finishes and is stored; then the runner stops
    settled = client.get(f"/v1/jobs/{accepted['id']}").json()
    time.sleep(0.5)
    later = client.get(f"/v1/jobs/{accepted['id']}").json()
    assert later["state"] == "cancelled" and later["windows_done"] == settled["windows_done"] < later["windows_total"]
    assert client.get(f"/v1/jobs/{accepted['id']}/result").status_code == 409
    assert client.delete(f"/v1/jobs/{accepted['id']}").status_code == 200  # cancelling again is harmless


def test_listing_is_paged_newest_first(client, capture):
    ids = [_submit(client, document_json(capture, LabelingOptions(window=30)))["id"] for _ in range(3)]
    page = client.get("/v1/jobs", params={"limit": 2, "offset": 0}).json()
    assert [job["id"] for job in page["jobs"]] == ids[::-1][:2] and page["total"] >= 3
    following = client.get("/v1/jobs", params={"limit": 2, "offset": 2}).json()
    assert following["jobs"][0]["id"] == ids[0]


def test_formulations_health_and_metrics(client, capture):
    names = [f["name"] for f in client.get("/v1/formulations").json()]
    assert "lp-l1" in names and "ilp" in names
    ilp = next(f for f in client.get("/v1/formulations").json() if f["name"] == "ilp")
    assert {"name": "time_limit", "default": 60.0} in [{k: p[k] for k in ("name", "default")} for p in ilp["parameters"]]
    job = wait_for(client, _submit(client, document_json(capture, OPTIONS))["id"])
    for listed in client.get("/v1/jobs", params={"limit": 500}).json()["jobs"]:
        wait_for(client, listed["id"])
    assert client.get("/healthz").json() == {"status": "ok"}
    states = [j["state"] for j in client.get("/v1/jobs", params={"limit": 500}).json()["jobs"]]
    metrics = client.get("/metrics").text
    done = float(next(line.split()[-1] for line in metrics.splitlines() if line.startswith('markerflow_jobs{state="done"}')))
    solved = float(next(line.split()[-1] for line in metrics.splitlines() if line.startswith("markerflow_windows_solved_total")))
    count = float(next(
        line.split()[-1] for line in metrics.splitlines() if line.startswith("markerflow_window_solve_seconds_count")
    ))
    assert done == states.count("done") and solved == count >= job["windows_total"]


def test_openapi_documents_every_route_with_examples(client):
    schema = client.get("/openapi.json").json()
    for path, operations in schema["paths"].items():
        for method, operation in operations.items():
            success = operation["responses"].get("200") or operation["responses"]["202"]
            assert success.get("content"), f"{method} {path} has no response content"
    jobs = schema["paths"]["/v1/jobs"]["post"]["requestBody"]["content"]
    assert set(jobs) == {"application/json", "multipart/form-data"}
    example = next(iter(jobs["application/json"]["examples"].values()))["value"]
    answer = client.post("/v1/solve", json=example)
    assert answer.status_code == 200 and answer.json()["certificate"]["integral"]
    assert "CaptureDocument" in schema["components"]["schemas"] and "CameraDocument" in schema["components"]["schemas"]


def test_a_stream_whose_job_is_removed_between_polls_ends_with_a_removed_event():
    """Cancelled and removed between two polls, the job vanished under the stream: the server
    logged NoResultFound and cut the stream off with no last event."""
    class Removed:  # the store as the stream's next poll finds it
        def get(self, job_id: str) -> None:
            return None

    async def collect() -> list[str]:
        return [event async for event in job_events(Removed(), "abc", 0.01)]  # type: ignore[arg-type]

    assert asyncio.run(collect()) == ['event: removed\ndata: {"id": "abc"}\n\n']
