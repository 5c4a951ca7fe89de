"""``markerflow serve``: the HTTP service under uvicorn."""

from __future__ import annotations

from pathlib import Path

from service.server.settings import load_settings


def run_serve(host: str | None, port: int | None, db: str | None, dask: str | None, config: Path | None) -> None:
    """Settings from the options, ``MARKERFLOW_*`` and ``config``; refuse an open bind without tokens."""
    import uvicorn

    from service.server.app import create_app

    settings = load_settings(config, host=host, port=port, db=database_url(db), dask=dask)
    app = create_app(settings)
    # A bounded graceful shutdown: open event streams must not hold a restart forever.
    uvicorn.run(app, host=settings.host, port=settings.port, timeout_graceful_shutdown=5, log_level="info")


def database_url(db: str | None) -> str | None:
    """``--db``: a URL as given; a plain path (no ``scheme://``) is a SQLite file there."""
    if db is None or "://" in db:
        return db
    return f"sqlite:///{db}"
