"""Jobs on a Dask cluster (a LocalCluster of worker processes) give what the in-process pool gives,
and a job the cluster gives up on fails with the reason instead of staying ``running``."""

from __future__ import annotations

import os
import sqlite3
import sys

import cloudpickle
import dask
import numpy as np
import pytest
from distributed import LocalCluster
from service_fixtures import document_json, generated_capture, nan_array, serving, wait_for

from service.capture.capture import LabelingOptions
from service.server import executor
from service.server.runner import run_job
from service.server.settings import Settings

OPTIONS = LabelingOptions(formulation="ilp", window=10)


def _run(settings: Settings, body: str) -> tuple[dict, dict]:
    with serving(settings) as client:
        answer = client.post("/v1/jobs", content=body, headers={"content-type": "application/json"})
        assert answer.status_code == 202
        job = wait_for(client, answer.json()["id"], timeout=120)
        return job, client.get(f"/v1/jobs/{job['id']}/result").json()


def test_a_job_on_a_dask_cluster_matches_the_in_process_run(tmp_path):
    body = document_json(generated_capture(frames=60, seed=8), OPTIONS)
    local_job, local = _run(Settings(db=f"sqlite:///{tmp_path / 'local.db'}"), body)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        dask_job, remote = _run(Settings(db=f"sqlite:///{tmp_path / 'dask.db'}", dask=cluster.scheduler_address), body)
    assert local_job["state"] == dask_job["state"] == "done"
    # Every window was computed in a Dask worker's process, not in this one.
    with sqlite3.connect(tmp_path / "dask.db") as db:
        workers = {w for (w,) in db.execute("SELECT worker FROM windows")}
    assert workers and not any(w.endswith(f":{os.getpid()}") for w in workers)
    assert remote["markers"] == local["markers"]
    for key in ("positions", "filled"):
        assert np.array_equal(nan_array(remote[key]), nan_array(local[key]), equal_nan=True)
    assert remote["occluded"] == local["occluded"]
    assert [w["cost"] for w in dask_job["windows"]] == [w["cost"] for w in local_job["windows"]]


@pytest.mark.parametrize("db", ["sqlite:///relative.db"])
def test_sqlite_paths_are_made_absolute_for_workers_elsewhere(db, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert Settings(db=db).db == f"sqlite:///{tmp_path / 'relative.db'}"


def _two_windows_then_raise(db_url: str, job_id: str) -> str:
    """A task that stores two windows and then errs (as a worker's broken environment would)."""
    stops = iter([False, True])
    run_job(db_url, job_id, lambda: next(stops))
    raise RuntimeError("the worker's environment is broken")


def _lose_the_worker(db_url: str, job_id: str) -> str:
    os._exit(1)  # the worker process dies, as under the OOM killer


def test_a_job_the_cluster_gives_up_on_fails_with_the_reason_and_keeps_its_windows(tmp_path, monkeypatch):
    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the workers cannot import this test module
    settings = Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}")
    body = document_json(generated_capture(frames=60, seed=8), OPTIONS)
    # The worker is lost twice: once, then once more on the retry (allowed-failures + 1 times).
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 1}),
        LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        serving(settings.model_copy(update={"dask": cluster.scheduler_address})) as client,
    ):
        ended = []
        for task in (_two_windows_then_raise, _lose_the_worker):  # one after the other: one worker, two fates
            monkeypatch.setattr(executor, "run_job", task)
            answer = client.post("/v1/jobs", content=body, headers={"content-type": "application/json"})
            ended.append(wait_for(client, answer.json()["id"], timeout=60))
        erred, lost = ended
        partial = client.get(f"/v1/jobs/{erred['id']}/result", params={"partial": "true"})
    assert erred["state"] == "failed" and erred["windows_done"] == 2 and len(erred["windows"]) == 2
    assert erred["error"] == "the Dask cluster gave up on the job (RuntimeError: the worker's environment is broken)"
    assert partial.status_code == 200 and not all(map(all, partial.json()["occluded"]))
    assert lost["state"] == "failed" and "KilledWorker" in lost["error"] and lost["windows_done"] == 0


def test_a_job_queued_on_a_cluster_without_a_worker_says_why(tmp_path):
    """It sat ``queued`` with nothing said; once a worker connects it runs."""
    body = document_json(generated_capture(frames=30, seed=3), OPTIONS)
    with (
        LocalCluster(n_workers=0, processes=True, dashboard_address=None) as cluster,
        serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}", dask=cluster.scheduler_address)) as client,
    ):
        answer = client.post("/v1/jobs", content=body, headers={"content-type": "application/json"})
        assert answer.status_code == 202
        said = f"the Dask cluster at {cluster.scheduler_address} has no worker: queued jobs wait until one connects"
        assert any(line.startswith(said) for line in answer.json()["warnings"]), answer.json()
        status = client.get(f"/v1/jobs/{answer.json()['id']}").json()
        assert status["state"] == "queued" and any(line.startswith(said) for line in status["warnings"])
        cluster.scale(1)
        done = wait_for(client, answer.json()["id"], timeout=120)
    assert done["state"] == "done" and not any(line.startswith(said) for line in done["warnings"])
