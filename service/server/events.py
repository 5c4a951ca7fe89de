"""Server-sent events of a job's progress: one ``window`` event per finished window, and a
``state`` event at each change of state; the stream ends when the job does (with a
``removed`` event when the job was removed in between).

The stream polls the store (every ``events_poll_seconds``, 0.2 s by default) rather than
listening to the runner: the runner may be another process or a Dask worker, and the
store is what they share. The wire format (``event:``/``data:`` lines) is three lines of
code, so no SSE library is pulled in for it. A token may hold
``max_event_streams_per_token`` streams open at once (``EventStreams``).
"""

from __future__ import annotations

import asyncio
import json
from collections import Counter
from collections.abc import AsyncIterator, Callable

from fastapi import HTTPException
from fastapi.responses import StreamingResponse
from starlette.concurrency import run_in_threadpool
from starlette.types import Receive, Scope, Send

from service.server.schemas import JobSummary, WindowSummary
from service.server.store import ACTIVE, JobStore


def sse(event: str, data: dict) -> str:
    return f"event: {event}\ndata: {json.dumps(data)}\n\n"


async def job_events(store: JobStore, job_id: str, poll_seconds: float,
                     closing: Callable[[], bool] = lambda: False) -> AsyncIterator[str]:
    """The job's events until it ends, or until ``closing()`` (a shutdown: the client reconnects)."""
    sent, state = -1, None
    while True:
        # The job first, then its windows: a job seen terminal has all its windows stored.
        job = await run_in_threadpool(store.get, job_id)
        if job is None:  # cancelled and removed between two polls: said, not a broken stream
            yield sse("removed", {"id": job_id})
            return
        for window in await run_in_threadpool(store.windows, job_id, sent):
            sent = window.index
            summary = WindowSummary.of_stored(window).model_dump()
            yield sse("window", {"windows_done": window.index + 1, "windows_total": job.windows_total, "window": summary})
        if job.state != state:
            state = job.state
            yield sse("state", JobSummary.of(job).model_dump(mode="json"))
        if state not in ACTIVE or closing():
            return
        await asyncio.sleep(poll_seconds)


class EventStreams:
    """The event streams open per owner (token): past ``limit`` a new one answers 429.

    Each open stream polls the store, so a token holding hundreds of them slows every
    caller; counted from the response's creation to the end of its sending (the client
    leaving included). One event loop touches the counts, so no lock.
    """

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.closing = False  # a shutdown began: every stream ends at its next poll
        self._open: Counter[str] = Counter()

    def close_all(self) -> None:
        self.closing = True

    def response(self, owner: str, store: JobStore, job_id: str, poll_seconds: float) -> StreamingResponse:
        """The job's events as a ``text/event-stream`` response, counted against ``owner``.

        Raises:
            HTTPException: 429, ``owner`` has ``limit`` streams open.
        """
        if self._open[owner] >= self.limit:
            raise HTTPException(429, f"{self.limit} event streams are open for this token, the limit "
                                     "(max_event_streams_per_token); close one first", headers={"Retry-After": "1"})
        self._open[owner] += 1
        events = job_events(store, job_id, poll_seconds, lambda: self.closing)
        return _CountedStream(events, lambda: self._close(owner))

    def _close(self, owner: str) -> None:
        self._open[owner] -= 1
        if not self._open[owner]:
            del self._open[owner]


class _CountedStream(StreamingResponse):
    def __init__(self, events: AsyncIterator[str], closed: Callable[[], None]) -> None:
        super().__init__(events, media_type="text/event-stream", headers={"Cache-Control": "no-cache"})
        self._closed = closed

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        try:
            await super().__call__(scope, receive, send)
        finally:
            self._closed()
