"""``markerflow serve``: the HTTP service under uvicorn."""

from __future__ import annotations

from pathlib import Path

from service.server.settings import load_settings


def run_serve(host: str | None, port: int | None, db: str | None, dask: str | None, config: Path | None) -> None:
    """Settings from the options, ``MARKERFLOW_*`` and ``config``; refuse an open bind without tokens."""
    from service.server.app import create_app
    from service.server.serving import service_server

    settings = load_settings(config, host=host, port=port, db=database_url(db), dask=dask)
    # Read timeouts, and a bounded shutdown: neither a stalled client nor a long window holds a restart.
    service_server(create_app(settings), settings, settings.host, settings.port, "info").run()


def database_url(db: str | None) -> str | None:
    """``--db``: a URL as given; a plain path (no ``scheme://``) is a SQLite file there."""
    if db is None or "://" in db:
        return db
    return f"sqlite:///{db}"
