"""Server-sent events of a job's progress: one ``window`` event per finished window, and a
``state`` event at each change of state; the stream ends when the job does.

The stream polls the store (every ``events_poll_seconds``, 0.2 s by default) rather than
listening to the runner: the runner may be another process or a Dask worker, and the
store is what they share. The wire format (``event:``/``data:`` lines) is three lines of
code, so no SSE library is pulled in for it.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator

from starlette.concurrency import run_in_threadpool

from service.server.schemas import JobSummary, WindowSummary
from service.server.store import ACTIVE, JobStore


def sse(event: str, data: dict) -> str:
    return f"event: {event}\ndata: {json.dumps(data)}\n\n"


async def job_events(store: JobStore, job_id: str, poll_seconds: float) -> AsyncIterator[str]:
    sent, state = -1, None
    while True:
        # The job first, then its windows: a job seen terminal has all its windows stored.
        job = await run_in_threadpool(store.known, job_id)
        for window in await run_in_threadpool(store.windows, job_id, sent):
            sent = window.index
            summary = WindowSummary.of_stored(window).model_dump()
            yield sse("window", {"windows_done": window.index + 1, "windows_total": job.windows_total, "window": summary})
        if job.state != state:
            state = job.state
            yield sse("state", JobSummary.of(job).model_dump(mode="json"))
        if state not in ACTIVE:
            return
        await asyncio.sleep(poll_seconds)
