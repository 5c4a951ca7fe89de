"""A job the store fails under (a database restart, a full disk) is run again, not stranded.

Before, the worker's own ``fail`` and the watcher's raised while the database was down, and
the job stayed ``running`` with nothing running it until the server restarted.
"""

from __future__ import annotations

import json
import threading

import pytest
from sqlalchemy.exc import OperationalError
from test_service_security import small_document

from service.server import executor, runner
from service.server.job_process import StoreLost
from service.server.store import JobStore, store_for

STORE_DOWN = OperationalError("INSERT INTO windows", {}, Exception("server closed the connection unexpectedly"))


@pytest.fixture()
def db(tmp_path) -> str:
    return f"sqlite:///{tmp_path / 'jobs.db'}"


def _job(db: str) -> str:
    document = {**small_document(frames=7), "window": 3}  # three windows
    job, _ = store_for(db).add("local", "json", json.dumps(document).encode(), 3)
    return job.id


def test_a_window_the_store_cannot_save_leaves_the_job_to_be_run_again(db, monkeypatch):
    job_id = _job(db)
    save = JobStore.save_window
    calls = []

    def down_at_the_second(store, *args):
        calls.append(1)
        if len(calls) == 2:
            raise STORE_DOWN
        return save(store, *args)

    monkeypatch.setattr(JobStore, "save_window", down_at_the_second)
    with pytest.raises(OperationalError):
        runner.run_job(db, job_id)
    job = store_for(db).known(job_id)
    assert job.state == "running" and job.windows_done == 1 and job.error is None  # not failed by the outage
    assert runner.run_job(db, job_id) == "done"  # resumed after its stored window
    assert store_for(db).known(job_id).windows_done == 3


class _FlakyWatch:
    """A JobWatch whose store fails under the first ``failures`` runs."""

    runs: list[str] = []
    failures = 1

    def __init__(self, context, db_url: str, job_id: str) -> None:
        self.job_id = job_id

    def run(self) -> None:
        _FlakyWatch.runs.append(self.job_id)
        if len(_FlakyWatch.runs) <= _FlakyWatch.failures:
            raise StoreLost(f"job {self.job_id}: the store failed under its worker")


def _executor(db: str, monkeypatch, failures: int) -> executor.ProcessPoolExecutor:
    _FlakyWatch.runs, _FlakyWatch.failures = [], failures
    monkeypatch.setattr(executor, "JobWatch", _FlakyWatch)
    monkeypatch.setattr(executor, "STORE_RETRY_SECONDS", (0.01, 0.01))
    return executor.ProcessPoolExecutor(db, max_parallel_jobs=1, grace_seconds=1.0)


def _wait_for(condition, seconds: float = 10.0) -> None:
    done = threading.Event()
    for _ in range(int(seconds / 0.02)):
        if condition():
            return
        done.wait(0.02)
    raise AssertionError("timed out")


def test_the_executor_runs_a_job_again_after_the_store_failed_under_it(db, monkeypatch):
    job_id = _job(db)
    pool = _executor(db, monkeypatch, failures=1)
    pool.submit(job_id)
    _wait_for(lambda: len(_FlakyWatch.runs) == 2)
    pool.close()
    assert _FlakyWatch.runs == [job_id, job_id] and store_for(db).known(job_id).state == "queued"


def test_a_job_the_store_keeps_failing_under_is_failed_once_the_pauses_run_out(db, monkeypatch):
    job_id = _job(db)
    pool = _executor(db, monkeypatch, failures=10)
    pool.submit(job_id)
    _wait_for(lambda: store_for(db).known(job_id).state == "failed")
    pool.close()
    assert len(_FlakyWatch.runs) == 3  # the first run and one per pause
    assert store_for(db).known(job_id).error.startswith("the job store failed 3 times; last: job ")


def test_requests_while_the_store_is_down_are_503_with_retry_after(db, monkeypatch):
    """They were the 500 of a bug ("internal error"), /healthz included."""
    from service_fixtures import serving

    from service.server.settings import Settings

    with serving(Settings(db=db, retry_after_seconds=9)) as client:
        assert client.get("/healthz").status_code == 200

        def down(store, *args):
            raise STORE_DOWN

        monkeypatch.setattr(JobStore, "queued", down)
        for answer in (client.get("/healthz"), client.post("/v1/jobs", json=small_document())):
            assert answer.status_code == 503 and answer.headers["retry-after"] == "9"
            assert answer.json() == {"message": "the job store is not answering; retry later"}


class _TakenWatch(_FlakyWatch):
    """A JobWatch whose first worker found another runner holding the job."""

    def run(self) -> bool:  # type: ignore[override]
        _FlakyWatch.runs.append(self.job_id)
        return len(_FlakyWatch.runs) == 1


def test_a_job_another_runner_holds_is_run_here_once_it_stops_moving(db, monkeypatch):
    """Two servers on one store: the one whose runner lost the race for a window backed off
    for good, and when the other server stopped the job stayed running with no runner."""
    job_id = _job(db)
    pool = _executor(db, monkeypatch, failures=0)
    monkeypatch.setattr(executor, "JobWatch", _TakenWatch)
    monkeypatch.setattr(executor, "STALE_SECONDS", 0.2)
    monkeypatch.setattr(executor, "STANDBY_POLL_SECONDS", 0.02)
    pool.submit(job_id)
    _wait_for(lambda: len(_FlakyWatch.runs) == 2)
    pool.close()
    assert _FlakyWatch.runs == [job_id, job_id]


class _EndedTask:
    """A Dask future's end, as ``DaskExecutor._done`` sees it."""

    def __init__(self, status: str) -> None:
        self.status = status


def test_a_dask_task_the_cluster_dropped_is_submitted_again(db, monkeypatch):
    """Scheduler and worker killed together: the task ended neither finished nor erred, and the
    job stayed running with nothing running it until the server restarted."""
    job_id = _job(db)
    submitted: list[str] = []
    dask_pool = object.__new__(executor.DaskExecutor)  # no cluster: only the done callback is exercised
    dask_pool.db_url, dask_pool._futures, dask_pool._drops = db, {}, {}
    monkeypatch.setattr(dask_pool, "submit", submitted.append, raising=False)
    dask_pool._done(job_id, "key", _EndedTask("cancelled"))
    assert submitted == [job_id] and store_for(db).known(job_id).state == "queued"
    for _ in executor.STORE_RETRY_SECONDS:
        dask_pool._done(job_id, "key", _EndedTask("lost"))
    dropped = len(executor.STORE_RETRY_SECONDS) + 1  # submitted again after each drop but the last
    assert store_for(db).known(job_id).error == f"the Dask cluster dropped the job's task {dropped} times (last: lost)"
    dask_pool._done(job_id, "key", _EndedTask("finished"))  # a finished task is the runner's business
    assert len(submitted) == len(executor.STORE_RETRY_SECONDS)
