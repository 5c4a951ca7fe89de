"""Nothing runs or waits forever, and a failed window never loses the others (issues 14 and 15).

A window that raises fails its job with the window's index and keeps the stored windows
(``result?partial=true``); a cancel kills the running window's worker process; SIGTERM
exits within the grace period and leaves the job resumable.
"""

from __future__ import annotations

import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time

import httpx
import numpy as np
import psutil
from service_fixtures import (
    REPO,
    ServerProcess,
    document_json,
    generated_capture,
    nan_array,
    resumed_result,
    serving,
    wait_for,
)

from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.server import runner
from service.server.runner import run_job
from service.server.settings import Settings
from service.server.store import store_for

JSON = {"content-type": "application/json"}
# Two ~6 s windows (ILP without its LP shortcut over 200 frames of a crowded scene): a cancel
# or a shutdown always lands inside one.
SLOW = LabelingOptions(formulation={"name": "ilp", "lp_first": False}, window=200)
# Three windows of 0.3 to 0.5 s: a job that a restarted server finishes quickly.
MEDIUM = LabelingOptions(formulation={"name": "ilp", "lp_first": False}, window=40)


def _slow_body() -> str:
    return document_json(generated_capture(frames=402, seed=3, ghosts_per_frame=15.0), SLOW)


class _FailsAtWindow2(CaptureLabeling):
    def windows(self, after=None, progress=None, observer=None):
        for outcome in super().windows(after, progress, observer):
            yield outcome
            if outcome.index == 1:
                raise RuntimeError("the solver blew up")


def test_a_resumed_job_drops_the_note_its_dead_runner_left(tmp_path, monkeypatch):
    """After a restart mid second pass the job read "second pass: 58 of 58 windows" until the
    new runner's pass counted again from 0."""
    capture, options = generated_capture(frames=30, seed=5), LabelingOptions(window=10, second_pass=False)
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    store = store_for(db)
    job, _ = store.add("local", "json", document_json(capture, options).encode(), CaptureLabeling(capture, options).n_windows)
    store.note(job.id, "second pass: 3 of 3 windows")  # what the runner that died had written
    seen: list[list[str]] = []

    class Watching(CaptureLabeling):
        def windows(self, *args, **kwargs):
            seen.append(store.warnings(job.id))  # what a client reads while this runner labels
            return super().windows(*args, **kwargs)

    monkeypatch.setattr(runner, "CaptureLabeling", Watching)
    assert run_job(db, job.id) == "done"
    assert seen == [[]]


def test_a_window_that_raises_fails_the_job_and_keeps_the_windows_before_it(tmp_path, monkeypatch):
    capture, options = generated_capture(frames=60, seed=5), LabelingOptions(formulation="ilp", window=10)
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    windows_total = CaptureLabeling(capture, options).n_windows
    job, _ = store_for(db).add("local", "json", document_json(capture, options).encode(), windows_total)
    monkeypatch.setattr(runner, "CaptureLabeling", _FailsAtWindow2)
    assert run_job(db, job.id) == "failed"
    monkeypatch.undo()

    expected, stats = CaptureLabeling(capture, options).label()
    labeled = stats[1].last + 1  # frames 0 .. last frame of window 1
    with serving(Settings(db=db)) as client:
        status = client.get(f"/v1/jobs/{job.id}").json()
        assert status["state"] == "failed"
        assert status["error"] == "window 2: internal error: RuntimeError: the solver blew up"
        assert [w["index"] for w in status["windows"]] == [0, 1] and status["windows_done"] == 2
        assert client.get(f"/v1/jobs/{job.id}/result").status_code == 409
        partial = client.get(f"/v1/jobs/{job.id}/result", params={"partial": "true"}).json()
        as_csv = client.get(f"/v1/jobs/{job.id}/result", params={"partial": "true", "format": "csv"})
        assert as_csv.status_code == 200  # named as partial: it was named as a whole result would be
        assert f'filename="markerflow_labeled-{job.id[:8]}-partial-failed.csv"' in as_csv.headers["content-disposition"]
    positions, occluded = nan_array(partial["positions"]), np.array(partial["occluded"])
    assert np.array_equal(positions[:labeled], expected.positions[:labeled], equal_nan=True)
    assert np.array_equal(occluded[:labeled], expected.occluded[:labeled])
    assert occluded[labeled:].all() and np.isnan(positions[labeled:]).all() and not occluded[:labeled].all()


def test_a_failed_jobs_labels_are_assembled_once_for_every_view(tmp_path, monkeypatch):
    """Each view of a failed or cancelled job's page and plots assembled its windows again
    (30-40 s per request on a 38,250-frame take)."""
    from service.web import job_data

    capture, options = generated_capture(frames=60, seed=5), LabelingOptions(formulation="ilp", window=10)
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    job, _ = store_for(db).add("local", "json", document_json(capture, options).encode(),
                               CaptureLabeling(capture, options).n_windows)
    monkeypatch.setattr(runner, "CaptureLabeling", _FailsAtWindow2)
    assert run_job(db, job.id) == "failed"
    assembled = []
    real = job_data.stored_windows_trajectories
    monkeypatch.setattr(job_data, "stored_windows_trajectories", lambda *a: assembled.append(1) or real(*a))
    with serving(Settings(db=db)) as client:
        for path in ("", "/plots/timeline.svg", "/plots/trajectories.svg", ""):
            assert client.get(f"/jobs/{job.id}{path}").status_code == 200
    assert len(assembled) == 1


def test_a_jobs_second_pass_is_said_while_it_runs_and_gone_once_done(tmp_path, monkeypatch):
    """The progress stood at N/N, with nothing said, for as long as the first pass took."""
    from service.server.store import JobStore

    capture, options = generated_capture(frames=60, seed=5), LabelingOptions(window=10)
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    store = store_for(db)
    job, _ = store.add("local", "json", document_json(capture, options).encode(), CaptureLabeling(capture, options).n_windows)
    said: list[list[str]] = []
    noted = JobStore.note
    monkeypatch.setattr(JobStore, "note", lambda self, job_id, line: (noted(self, job_id, line),
                                                                     said.append(self.warnings(job_id)))[0])
    assert run_job(db, job.id) == "done"
    assert said and said[-1][0].startswith(f"second pass: {len(said)} of {len(said)} windows")
    assert not any(line.startswith("second pass") for line in store.warnings(job.id))


def _job_workers() -> list[psutil.Process]:
    """The job worker processes this test process started (children of its forkserver)."""
    return [p for p in psutil.Process().children(recursive=True)
            if "forkserver" in " ".join(p.parent().cmdline()) and p.status() != psutil.STATUS_ZOMBIE]


def test_cancel_stops_the_running_window_within_a_second(tmp_path):
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}", shutdown_grace_seconds=0.5)) as client:
        job_id = client.post("/v1/jobs", content=_slow_body(), headers=JSON).json()["id"]
        deadline = time.monotonic() + 10
        while not _job_workers():
            assert time.monotonic() < deadline, "the job's worker did not start"
            time.sleep(0.02)
        [worker] = _job_workers()
        time.sleep(0.5)  # inside window 0 (~6 s)
        started = time.monotonic()
        assert client.delete(f"/v1/jobs/{job_id}").json()["state"] == "cancelled"
        gone, alive = psutil.wait_procs([worker], timeout=1.0)
        latency = time.monotonic() - started
        print(f"cancel latency: {latency:.3f} s")
        assert gone and not alive, "the window was still computing a second after DELETE"
        assert client.get(f"/v1/jobs/{job_id}").json()["windows_done"] == 0


def test_sigterm_exits_within_the_grace_period_and_the_job_resumes(tmp_path):
    db_path = tmp_path / "jobs.db"
    capture = generated_capture(frames=122, seed=3, ghosts_per_frame=6.0)
    grace = 0.5
    first = ServerProcess(f"sqlite:///{db_path}", tmp_path / "first.log", {"MARKERFLOW_SHUTDOWN_GRACE_SECONDS": str(grace)})
    try:
        with httpx.Client(base_url=first.url, timeout=30) as client:
            job_id = client.post("/v1/jobs", content=document_json(capture, MEDIUM), headers=JSON).json()["id"]
            assert wait_for(client, job_id, states=("running",))["state"] == "running"
            # Open an event stream too: it must not hold the shutdown either.
            with client.stream("GET", f"/v1/jobs/{job_id}/events") as events:
                assert events.status_code == 200
                started = time.monotonic()
                os.kill(first.process.pid, signal.SIGTERM)
                first.process.wait(10)
        exit_seconds = time.monotonic() - started
    finally:
        first.stop()
    print(f"SIGTERM exit: {exit_seconds:.2f} s (grace {grace} s)")
    assert exit_seconds < grace + 2.0
    # a stop asked for is a clean exit (143 and "no output written" marked every systemd stop failed)
    assert first.process.returncode == 0 and "interrupted" not in (tmp_path / "first.log").read_text()
    with sqlite3.connect(db_path) as db:
        state, done, total = db.execute("SELECT state, windows_done, windows_total FROM jobs").fetchone()
    assert state == "running" and done < total, "the job is left resumable, mid-way"

    result, _ = resumed_result(f"sqlite:///{db_path}", tmp_path / "second.log", job_id, timeout=30)
    expected, _ = CaptureLabeling(capture, MEDIUM).label()
    assert np.array_equal(nan_array(result["positions"]), expected.positions, equal_nan=True)
    assert np.array_equal(np.array(result["occluded"]), expected.occluded)


def test_a_port_in_use_is_one_line_before_any_job_is_resumed(tmp_path):
    """uvicorn starts the app, which resumes the store's jobs, before it binds."""
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        run = subprocess.run([sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--db",
                              str(tmp_path / "jobs.db")], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and run.stderr.startswith(f"error: --port {port}: cannot listen on 127.0.0.1:{port}")
    assert "resumed" not in run.stderr + run.stdout


def _answer_of(port: int, request: bytes, timeout: float) -> tuple[bytes, float]:
    """Send ``request`` and read until the server closes the connection: (what it sent, seconds)."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as connection:
        connection.sendall(request)
        started, received = time.monotonic(), b""
        while chunk := connection.recv(4096):
            received += chunk
        return received, time.monotonic() - started


def test_stalled_requests_time_out_and_event_streams_are_limited_per_token(tmp_path):
    settings = Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}", read_timeout_seconds=0.5, max_event_streams_per_token=2,
                        shutdown_grace_seconds=0.5)
    with serving(settings) as client:
        port = client.base_url.port
        # A request head that never ends, and a body that stops: closed, and 408, after 0.5 s.
        closed, seconds = _answer_of(port, b"GET /v1/jobs HTTP/1.1\r\nHost: x\r\n", timeout=5)
        assert closed == b"" and 0.4 < seconds < 2
        stalled = b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n{"
        answer, seconds = _answer_of(port, stalled, timeout=5)
        assert answer.startswith(b"HTTP/1.1 408") and b"read_timeout_seconds" in answer and seconds < 2
        assert client.get("/v1/jobs").status_code == 200  # the server still serves

        job_id = client.post("/v1/jobs", content=_slow_body(), headers=JSON).json()["id"]
        url = f"/v1/jobs/{job_id}/events"
        with client.stream("GET", url) as first, client.stream("GET", url) as second:
            assert first.status_code == second.status_code == 200
            refused = client.get(url)
            assert refused.status_code == 429 and "max_event_streams_per_token" in refused.json()["message"]
        deadline = time.monotonic() + 5  # the closed streams are counted off once the server sees them go
        while True:
            with client.stream("GET", url) as again:
                if again.status_code != 429 or time.monotonic() > deadline:
                    break
            time.sleep(0.05)
        assert again.status_code == 200
        client.delete(f"/v1/jobs/{job_id}")


def test_a_window_finished_after_a_cancel_is_not_stored(tmp_path):
    """DELETE answered "cancelled, 116 windows" and a window finishing in the worker before
    it was stopped made it 117: the count a cancel answers must stay what it said."""
    capture = generated_capture(frames=40, seed=5)
    store = store_for(f"sqlite:///{tmp_path / 'jobs.db'}")
    options = LabelingOptions(window=10)
    labeling = CaptureLabeling(capture, options)
    job, _ = store.add("local", "json", document_json(capture, options).encode(), labeling.n_windows)
    first, second = list(labeling.windows())[:2]
    assert store.start(job.id) and store.save_window(job.id, first, "worker")
    assert store.cancel(job.id)
    assert not store.save_window(job.id, second, "worker")
    assert store.known(job.id).windows_done == 1 and [w.index for w in store.windows(job.id)] == [0]
