"""SIGKILL the server mid-job: on restart the job resumes after its last stored window,
recomputes none of the stored ones, and ends bit for bit where an uninterrupted run does.
On SQLite and on PostgreSQL (``store_url``)."""

from __future__ import annotations

import os
import signal
import time

import httpx
import numpy as np
from service_fixtures import ServerProcess, document_json, generated_capture, nan_array, resumed_result
from sqlalchemy import create_engine, text

from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.server.job_process import SERVER_POLL_SECONDS

# The ILP without its LP shortcut: ~40 ms a window, so the kill lands mid-job.
OPTIONS = LabelingOptions(formulation={"name": "ilp", "lp_first": False}, window=4)


def _stored(store_url: str, job_id: str) -> tuple[tuple, list[tuple]]:
    """The job's (state, windows_done, windows_total) and its stored windows' (index, worker, outcome)."""
    engine = create_engine(store_url)
    try:
        with engine.connect() as db:
            job = db.execute(text("SELECT state, windows_done, windows_total FROM jobs WHERE id = :id"),
                             {"id": job_id}).one()
            windows = db.execute(text('SELECT "index", worker, outcome FROM windows WHERE job_id = :id ORDER BY "index"'),
                                 {"id": job_id}).all()
        return tuple(job), [(index, worker, bytes(outcome)) for index, worker, outcome in windows]
    finally:
        engine.dispose()


def test_a_killed_job_resumes_from_its_last_stored_window(store_url, tmp_path):
    capture = generated_capture(frames=200, seed=7)
    first = ServerProcess(store_url, tmp_path / "first.log")
    try:
        with httpx.Client(base_url=first.url, timeout=30) as client:
            answer = client.post("/v1/jobs", content=document_json(capture, OPTIONS),
                                 headers={"content-type": "application/json"})
            assert answer.status_code == 202
            job_id = answer.json()["id"]
            deadline = time.monotonic() + 60
            while client.get(f"/v1/jobs/{job_id}").json()["windows_done"] < 3:
                assert time.monotonic() < deadline
                time.sleep(0.02)
        os.kill(first.process.pid, signal.SIGKILL)
        first.process.wait(10)
        time.sleep(3 * SERVER_POLL_SECONDS)  # its job worker notices the server is gone, and exits
    finally:
        first.stop()

    (state, done, total), before = _stored(store_url, job_id)
    assert state == "running" and 3 <= done < total, "the kill must land mid-job"
    assert [row[0] for row in before] == list(range(done))
    # One job worker process of the first server computed them (not the server itself).
    first_workers = {row[1].rsplit(":", 1)[1] for row in before}
    assert len(first_workers) == 1 and str(first.process.pid) not in first_workers

    result, second_pid = resumed_result(store_url, tmp_path / "second.log", job_id)

    (state, finished, total), after = _stored(store_url, job_id)
    assert state == "done" and finished == total and [row[0] for row in after] == list(range(total))
    # The windows stored before the kill are the very same rows: kept, not recomputed.
    assert after[:done] == before
    second_workers = {row[1].rsplit(":", 1)[1] for row in after[done:]}
    assert len(second_workers) == 1 and second_workers.isdisjoint(first_workers | {str(second_pid)})

    expected, _ = CaptureLabeling(capture, OPTIONS).label()
    assert np.array_equal(nan_array(result["positions"]), expected.positions, equal_nan=True)
    assert np.array_equal(np.array(result["occluded"]), expected.occluded)
    assert np.array_equal(nan_array(result["filled"]), expected.filled, equal_nan=True)
