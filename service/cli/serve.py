"""``markerflow serve``: the HTTP service under uvicorn."""

from __future__ import annotations

import signal
import socket
from pathlib import Path

from service.errors import InputError
from service.server.settings import load_settings


def run_serve(host: str | None, port: int | None, db: str | None, dask: str | None, config: Path | None) -> None:
    """Settings from the options, ``MARKERFLOW_*`` and ``config``; refuse an open bind without tokens."""
    from service.server.app import create_app
    from service.server.serving import service_server

    settings = load_settings(config, host=host, port=port, db=database_url(db), dask=dask)
    check_store(settings.db)
    if settings.dask:
        check_dask(settings.dask)
    check_address(settings.host, settings.port)
    # Read timeouts, and a bounded shutdown: neither a stalled client nor a long window holds a restart.
    server = service_server(create_app(settings), settings, settings.host, settings.port, "info")
    # uvicorn drains on SIGTERM / Ctrl-C, then raises the signal again once it has stopped: by
    # then the service has stopped as asked, so it ends with 0, not as an interrupted command
    # that wrote no output (143 marked every systemd stop failed).
    stopped = {sig: signal.signal(sig, lambda *_: None) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        server.run()
    finally:
        for sig, handler in stopped.items():
            signal.signal(sig, handler)


def check_address(host: str, port: int) -> None:
    """Bind the address once before serving: uvicorn starts the app (which resumes the store's
    unfinished jobs) before it binds, so a port in use ran job work in a server that never started.

    Raises:
        InputError: ``--port P: cannot listen on HOST:P (<reason>)``.
    """
    if port == 0:  # any free port
        return
    try:
        with socket.create_server((host, port), family=socket.AF_INET6 if ":" in host else socket.AF_INET):
            pass
    except OSError as error:
        raise InputError(f"--port {port}: cannot listen on {host}:{port} ({error.strerror or error})") from None


def check_store(url: str) -> None:
    """Open the job store once before serving, so a database that cannot be opened is one
    line, not uvicorn's traceback of the app's start-up (170 lines).

    Raises:
        InputError: ``--db <url, password hidden>: cannot open the job store (<the driver's reason>)``.
    """
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import SQLAlchemyError

    from service.server.store import store_for

    shown = make_url(url).render_as_string(hide_password=True)
    try:
        store_for(url).engine.dispose()
    except SQLAlchemyError as error:
        reason = str(getattr(error, "orig", None) or error).strip().splitlines()[0]
        folder = " (does its folder exist, and can this user write there?)" if url.startswith("sqlite") else ""
        raise InputError(f"--db {shown}: cannot open the job store ({reason}){folder}") from None
    except ModuleNotFoundError as error:  # a dialect whose driver is not installed, e.g. mysql://
        raise InputError(f"--db {shown}: no database driver for it ({error.name} is not installed)") from None


DASK_CONNECT_SECONDS = 10.0  # a scheduler on the network answers in well under a second


def check_dask(address: str) -> None:
    """Reach the Dask scheduler once before serving: a wrong ``--dask`` was a 100-line start-up
    traceback, after a 30 s wait.

    Raises:
        InputError: ``--dask <address>: cannot reach the Dask scheduler (<reason>)``.
    """
    from distributed import Client

    try:
        Client(address, timeout=DASK_CONNECT_SECONDS).close()
    except (OSError, ValueError, TypeError) as error:  # timeouts are OSError; a malformed address ValueError
        reason = next(iter(str(error).splitlines()), type(error).__name__)
        raise InputError(f"--dask {address}: cannot reach the Dask scheduler ({reason})") from None


def database_url(db: str | None) -> str | None:
    """``--db``: a URL as given; a plain path (no ``scheme://``) is a SQLite file there."""
    if db is None or "://" in db:
        return db
    return f"sqlite:///{db}"
