"""Where jobs run: a bounded pool of job worker processes, or a Dask cluster.

The in-process pool watches each job from a thread and runs its windows in a worker
process of its own (``job_process``), so a cancel stops the window being computed and a
shutdown waits at most its grace period. More machines come from the Dask path, which
runs the very same ``run_job``.
"""

from __future__ import annotations

import logging
import threading
import time
import uuid
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Protocol

from sqlalchemy.exc import OperationalError

from service.server.job_process import JobWatch, StoreLost, worker_context
from service.server.runner import run_job
from service.server.store import ACTIVE, store_for

log = logging.getLogger("markerflow.server")
STORE_RETRY_SECONDS = (1.0, 4.0, 15.0, 60.0, 240.0)  # pauses before a job the store failed under runs again
# A job held by another runner that has not moved for this long is run here: longer than a
# window or a second pass takes (neither is stored until it ends), short against a restart.
STALE_SECONDS = 300.0
STANDBY_POLL_SECONDS = 5.0


class Executor(Protocol):
    def submit(self, job_id: str) -> None: ...

    def cancel(self, job_id: str) -> None: ...

    def stop_windows(self) -> None: ...

    def waiting(self) -> str | None:
        """Why a queued job may not start soon, when this executor knows of a reason."""

    def close(self) -> None: ...


class ProcessPoolExecutor:
    """Up to ``max_parallel_jobs`` jobs at once; each job's windows in order in its worker process.

    Args:
        grace_seconds: After a shutdown begins (``stop_windows``), running windows get this
            long to finish; then their workers are killed. Their jobs stay ``running`` and
            resume on restart after their last stored window.
    """

    def __init__(self, db_url: str, max_parallel_jobs: int, grace_seconds: float) -> None:
        self.db_url, self.grace_seconds = db_url, grace_seconds
        self._context = worker_context()
        self._pool = ThreadPoolExecutor(max_parallel_jobs, thread_name_prefix="markerflow-job")
        self._watches: dict[str, JobWatch] = {}
        self._deadline: float | None = None  # set when the shutdown begins
        self._lock = threading.Lock()
        self._store_failures: dict[str, int] = {}  # per job, in a row: see _retry_later
        self._closing = threading.Event()  # ends the stand-by watches

    def submit(self, job_id: str) -> None:
        self._pool.submit(self._watch, job_id)

    def _watch(self, job_id: str) -> None:
        with self._lock:
            if self._deadline is not None:
                return  # queued behind the pool when the shutdown began: resumed on restart
            watch = self._watches[job_id] = JobWatch(self._context, self.db_url, job_id)
        try:
            if watch.run():
                threading.Thread(target=self._stand_by, args=(job_id,), daemon=True,
                                 name=f"markerflow-standby-{job_id}").start()
            self._store_failures.pop(job_id, None)
        except (StoreLost, OperationalError) as error:
            self._retry_later(job_id, error)
        except Exception:  # a bug in the watch itself: the job stays where the store has it
            log.exception("watching job %s failed", job_id)
        finally:
            with self._lock:
                self._watches.pop(job_id, None)

    def _retry_later(self, job_id: str, error: Exception) -> None:
        """The store failed under the job (a database restart, a full disk): nothing runs it
        now, so it is submitted again after a growing pause (it resumes after its last stored
        window); after ``STORE_RETRY_SECONDS`` run out it is failed, if the store lets us."""
        failures = self._store_failures[job_id] = self._store_failures.get(job_id, 0) + 1
        reason = next(iter(str(error).splitlines()), type(error).__name__)
        if failures > len(STORE_RETRY_SECONDS):
            try:
                store_for(self.db_url).fail(job_id, f"the job store failed {failures} times; last: {reason}")
            except OperationalError:
                log.error("job %s: the job store keeps failing (%s); it stays unfinished until a restart", job_id, reason)
            return
        pause = STORE_RETRY_SECONDS[failures - 1]
        log.warning("job %s: the job store failed (%s); running it again in %g s", job_id, reason, pause)
        timer = threading.Timer(pause, self.submit, args=(job_id,))
        timer.daemon = True
        timer.start()

    def _stand_by(self, job_id: str) -> None:
        """Another runner holds the job (another server on this store stored a window first):
        watch it, and run it here once it has not moved for ``STALE_SECONDS`` (that server was
        stopped or died, and would resume it only on its own restart). Two runners are safe:
        a window is stored once, and the slower runner stops at it."""
        store, seen, since = store_for(self.db_url), None, time.monotonic()
        while not self._closing.wait(STANDBY_POLL_SECONDS):
            try:
                job = store.known(job_id)
            except OperationalError:
                continue
            if job.state not in ACTIVE:
                return
            if (job.updated_at, job.windows_done) != seen:
                seen, since = (job.updated_at, job.windows_done), time.monotonic()
            elif time.monotonic() - since > STALE_SECONDS:
                log.warning("job %s has not moved for %g s on its other runner; running it here", job_id, STALE_SECONDS)
                self.submit(job_id)
                return

    def cancel(self, job_id: str) -> None:
        """Stop the job's window now (the store already says ``cancelled``)."""
        with self._lock:
            watch = self._watches.get(job_id)
        if watch is not None:
            watch.cancelled.set()

    def stop_windows(self) -> None:
        """Begin the shutdown: workers stop between windows, or are killed at the grace deadline."""
        with self._lock:
            if self._deadline is None:
                self._deadline = time.monotonic() + self.grace_seconds
                for watch in self._watches.values():
                    watch.stop_by(self._deadline)

    def waiting(self) -> str | None:
        """None: a queued job starts as soon as a job ahead of it ends."""
        return None

    def close(self) -> None:
        self._closing.set()
        self.stop_windows()
        self._pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """Each job is one Dask task calling ``run_job`` with the store's URL.

    ``fire_and_forget``: the task runs to its end even if this server stops; a restarted
    server re-submits unfinished jobs, and the store's one-row-per-window key makes a
    second runner of the same job stop at its first stored window. A task the cluster
    gives up on (it raised, or its worker was lost ``distributed.scheduler.allowed-failures``
    + 1 times: ``KilledWorker``) fails its job with the reason; its stored windows stay.
    A cancel stops the job after its current window (a Dask task cannot be interrupted).
    """

    def __init__(self, db_url: str, address: str) -> None:
        from distributed import Client

        self.db_url = db_url
        self._client = Client(address)
        self._futures: dict[str, Any] = {}  # held so their done callbacks run
        self._drops: dict[str, int] = {}  # per job: tasks the cluster dropped (``_resubmit``)

    def submit(self, job_id: str) -> None:
        from distributed import fire_and_forget

        key = f"markerflow-job-{job_id}-{uuid.uuid4().hex[:8]}"
        if (idle := self.waiting()) is not None:
            log.warning("job %s: %s", job_id, idle)
        future = self._client.submit(run_job, self.db_url, job_id, key=key, pure=False)
        self._futures[key] = future
        future.add_done_callback(lambda done: self._done(job_id, key, done))
        fire_and_forget(future)

    def _done(self, job_id: str, key: str, future: Any) -> None:
        self._futures.pop(key, None)
        if future.status == "error":
            reason = _dask_reason(future.exception())
            if store_for(self.db_url).fail(job_id, f"the Dask cluster gave up on the job ({reason})"):
                log.warning("job %s failed on Dask: %s", job_id, reason)
        elif future.status != "finished":  # lost with the scheduler (cancelled, lost): no one runs it now
            self._resubmit(job_id, future.status)

    def _resubmit(self, job_id: str, status: str) -> None:
        """Submit a job whose task the cluster dropped again, if it is still unfinished; after
        ``len(STORE_RETRY_SECONDS)`` drops in a row it fails, saying so (it resumes after its
        last stored window either way)."""
        store = store_for(self.db_url)
        if store.known(job_id).state not in ACTIVE:
            return
        drops = self._drops[job_id] = self._drops.get(job_id, 0) + 1
        if drops > len(STORE_RETRY_SECONDS):
            store.fail(job_id, f"the Dask cluster dropped the job's task {drops} times (last: {status})")
            return
        log.warning("job %s: its Dask task ended %s; submitting it again", job_id, status)
        self.submit(job_id)

    def cancel(self, job_id: str) -> None:
        """Nothing to do here: the task sees the cancel in the store after its current window."""

    def stop_windows(self) -> None:
        """Nothing to do here: Dask tasks run on without this server (``fire_and_forget``)."""

    def waiting(self) -> str | None:
        """A cluster without a worker runs nothing: its queued jobs wait for one to connect."""
        if self._client.nthreads():
            return None
        return (f"the Dask cluster at {self._client.scheduler.address} has no worker: queued jobs wait until one "
                f"connects (dask worker {self._client.scheduler.address})")

    def close(self) -> None:
        self._client.close()


def _dask_reason(error: BaseException) -> str:
    """The cluster's reason in a few words: a ``KilledWorker``'s own text runs to a paragraph."""
    if type(error).__name__ == "KilledWorker":
        return "KilledWorker: its worker died on every try (distributed.scheduler.allowed-failures)"
    text = next(iter(str(error).splitlines()), "")
    return f"{type(error).__name__}: {text[:160]}"
