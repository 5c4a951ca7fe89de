"""How uvicorn serves the app: read timeouts on every connection, and a bounded shutdown.

uvicorn times out an idle keep-alive connection, but not one that never finishes sending
its request head: ``HeadTimeoutH11`` closes a connection whose head is not complete
``read_timeout_seconds`` after it opened (or after its previous response). A stalled
body is ``BodyLimit``'s (408). On SIGTERM or Ctrl-C, ``DrainingServer`` starts the job
workers' grace period at once, beside uvicorn's wait for open requests, so the process
exits within about ``shutdown_grace_seconds``.
"""

from __future__ import annotations

import asyncio
import copy
from types import FrameType

import uvicorn
from fastapi import FastAPI
from uvicorn.protocols.http.h11_impl import H11Protocol

from service.server.settings import Settings


def head_timeout_protocol(seconds: float) -> type[H11Protocol]:
    """uvicorn's h11 protocol, closing a connection whose request head takes over ``seconds``."""

    class HeadTimeoutH11(H11Protocol):
        _head_timer: asyncio.TimerHandle | None = None

        def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]  # as uvicorn's
            super().connection_made(transport)
            self._await_head()

        def on_response_complete(self) -> None:
            if not self.transport.is_closing():
                self._await_head()  # the next request's head (pipelined ones start below)
            super().on_response_complete()

        def handle_events(self) -> None:
            cycle = self.cycle
            super().handle_events()
            if self.cycle is not cycle:  # a request head arrived: its body has BodyLimit's timeout
                self._head_arrived()

        def connection_lost(self, exc: Exception | None) -> None:
            self._head_arrived()
            super().connection_lost(exc)

        def _await_head(self) -> None:
            self._head_arrived()
            self._head_timer = self.loop.call_later(seconds, self._head_timed_out)

        def _head_arrived(self) -> None:
            if self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None

        def _head_timed_out(self) -> None:
            if not self.transport.is_closing():
                self.transport.close()

    return HeadTimeoutH11


class DrainingServer(uvicorn.Server):
    """A uvicorn server whose exit signal also ends the event streams and begins the job
    workers' grace period."""

    def __init__(self, app: FastAPI, config: uvicorn.Config) -> None:
        super().__init__(config)
        self.app = app

    def handle_exit(self, sig: int, frame: FrameType | None) -> None:
        self.app.state.event_streams.close_all()  # they would hold uvicorn's wait for open requests
        executor = getattr(self.app.state, "executor", None)  # None before the lifespan has started
        if executor is not None:
            executor.stop_windows()
        super().handle_exit(sig, frame)


def service_server(app: FastAPI, settings: Settings, host: str, port: int, log_level: str) -> DrainingServer:
    """uvicorn serving ``app`` with the settings' read timeouts and shutdown grace."""
    # markerflow's own lines ("resumed 3 unfinished jobs", a store outage) through uvicorn's
    # handler at the same level: without a handler of their own only warnings showed
    logging_config = copy.deepcopy(uvicorn.config.LOGGING_CONFIG)
    logging_config["loggers"]["markerflow"] = {"handlers": ["default"], "level": log_level.upper(), "propagate": False}
    config = uvicorn.Config(
        app, host=host, port=port, log_level=log_level, http=head_timeout_protocol(settings.read_timeout_seconds),
        timeout_graceful_shutdown=max(1, round(settings.shutdown_grace_seconds)), log_config=logging_config,
    )
    return DrainingServer(app, config)
