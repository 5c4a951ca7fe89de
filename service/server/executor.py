"""Where jobs run: a bounded in-process thread pool, or a Dask cluster.

Threads, not processes: the heavy parts (HiGHS, numpy) release the GIL, a thread shares
the store's connection pool, and a shutdown can ask a thread to stop between windows.
More machines come from the Dask path, which runs the very same ``run_job``.
"""

from __future__ import annotations

import threading
import uuid
from concurrent.futures import ThreadPoolExecutor
from typing import Protocol

from service.server.runner import run_job


class Executor(Protocol):
    def submit(self, job_id: str) -> None: ...

    def close(self) -> None: ...


class ThreadExecutor:
    """Up to ``max_parallel_jobs`` jobs at once; each job's windows in order in one thread."""

    def __init__(self, db_url: str, max_parallel_jobs: int) -> None:
        self.db_url = db_url
        self._pool = ThreadPoolExecutor(max_parallel_jobs, thread_name_prefix="markerflow-job")
        self._stopping = threading.Event()

    def submit(self, job_id: str) -> None:
        self._pool.submit(run_job, self.db_url, job_id, self._stopping.is_set)

    def close(self) -> None:
        """Running jobs stop after their current window and stay ``running``, resumed on restart."""
        self._stopping.set()
        self._pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """Each job is one Dask task calling ``run_job`` with the store's URL.

    ``fire_and_forget``: the task runs to its end even if this server stops; a restarted
    server re-submits unfinished jobs, and the store's one-row-per-window key makes a
    second runner of the same job stop at its first stored window.
    """

    def __init__(self, db_url: str, address: str) -> None:
        from distributed import Client

        self.db_url = db_url
        self._client = Client(address)

    def submit(self, job_id: str) -> None:
        from distributed import fire_and_forget

        key = f"markerflow-job-{job_id}-{uuid.uuid4().hex[:8]}"
        fire_and_forget(self._client.submit(run_job, self.db_url, job_id, key=key, pure=False))

    def close(self) -> None:
        self._client.close()
