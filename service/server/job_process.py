"""One job's windows in a worker process of its own, so a cancel or a shutdown can stop a
window in the middle: the process is killed, which a thread in a solver's C code cannot be.

Killing is safe: every window is one committed transaction (see ``store``), so a killed
worker leaves the job at its last stored window, and a restart resumes from there.
Processes come from a *forkserver* that imported the runner once: a fork of it starts a
job in milliseconds, and the server's own threads are never forked.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import time
from multiprocessing.context import ForkServerContext

from sqlalchemy.exc import OperationalError

from service.server.runner import run_job
from service.server.store import ACTIVE, JobStore, store_for

POLL_SECONDS = 0.02  # how often a watcher looks at its process (cancel latency is about this)
STORE_POLL_SECONDS = 0.5  # how often it asks the store whether another server cancelled the job
SERVER_POLL_SECONDS = 0.2  # how often a worker checks that its server is still there
WORKER_NICENESS = 5  # windows yield the CPU to the server's requests (and its upload readers)
STORE_LOST_EXIT = 75  # EX_TEMPFAIL: the worker stopped because the store failed; run the job again


class StoreLost(Exception):
    """The job's worker stopped because the store failed under it; the job has no runner now."""


def worker_context() -> ForkServerContext:
    """The forkserver context, with the runner imported before any job forks."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["service.server.runner"])
    return context


def _work(db_url: str, job_id: str, server_pid: int) -> None:
    """The worker process: the job's windows; SIGTERM stops it between windows."""
    stopping = threading.Event()
    signal.signal(signal.SIGTERM, lambda _signal, _frame: stopping.set())
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the server, which stops its workers
    threading.Thread(target=_exit_with_server, args=(server_pid,), daemon=True).start()
    os.nice(WORKER_NICENESS)
    try:
        run_job(db_url, job_id, stopping.is_set)
    except OperationalError:
        sys.exit(STORE_LOST_EXIT)


def _exit_with_server(server_pid: int) -> None:
    """End this worker once the server is gone (SIGKILL, the OOM killer), so no orphan writes
    to the store beside the restarted server's worker. Its parent is the forkserver, so
    ``getppid`` cannot tell; the server's pid is asked directly."""
    while True:
        time.sleep(SERVER_POLL_SECONDS)
        try:
            os.kill(server_pid, 0)
        except ProcessLookupError:
            os._exit(1)


class JobWatch:
    """Run the job in a worker process and wait for it; kill it on cancel or at the shutdown deadline."""

    def __init__(self, context: ForkServerContext, db_url: str, job_id: str) -> None:
        self.db_url, self.job_id = db_url, job_id
        self.cancelled = threading.Event()  # set when this server cancels (the store is asked too, less often)
        self._deadline: float | None = None  # monotonic seconds at which a shutdown kills the worker
        self._process = context.Process(target=_work, args=(db_url, job_id, os.getpid()), daemon=True,
                                        name=f"markerflow-job-{job_id}")

    def stop_by(self, deadline: float) -> None:
        """A shutdown: the worker stops after its window (SIGTERM), or is killed at ``deadline``."""
        self._deadline = deadline
        if self._process.is_alive():
            self._process.terminate()

    def run(self) -> bool:
        """Until the worker ends; a worker that dies by itself (a crash, the OOM killer) fails the
        job. True when the worker ended leaving the job active in the store, not stopped by this
        server: another runner stored a window first and holds the job (``WindowTaken``)."""
        store = store_for(self.db_url)
        self._process.start()
        asked = time.monotonic()
        while self._process.is_alive():
            self._process.join(POLL_SECONDS)
            if time.monotonic() - asked > STORE_POLL_SECONDS:
                asked = time.monotonic()
                if self._state(store) not in ACTIVE:
                    self.cancelled.set()
            if self.cancelled.is_set() or (self._deadline is not None and time.monotonic() > self._deadline):
                self._process.kill()
                self._process.join()
                return False
        if self._process.exitcode == STORE_LOST_EXIT and self._deadline is None:
            raise StoreLost(f"job {self.job_id}: the store failed under its worker")
        if self._process.exitcode and self._deadline is None:
            store.fail(self.job_id, f"the job's worker process died ({_exit_reason(self._process.exitcode)})")
            return False
        return self._deadline is None and self._state(store) in ACTIVE

    def _state(self, store: JobStore) -> str:
        """The job's state, or "running" while the store does not answer (the worker finds out itself)."""
        try:
            return store.known(self.job_id).state
        except OperationalError:
            return "running"


def _exit_reason(exitcode: int) -> str:
    if exitcode < 0:
        return f"killed by {signal.Signals(-exitcode).name}"
    return f"exit status {exitcode}"
