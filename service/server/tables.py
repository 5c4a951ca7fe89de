"""The store's tables, and the SQLite connection settings (the one SQLite-specific place)."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from typing import Literal

from sqlalchemy import ForeignKey, Index, LargeBinary, String, Text, create_engine, event, inspect, text
from sqlalchemy.engine import Engine
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import DeclarativeBase, Mapped, deferred, mapped_column

JobState = Literal["queued", "running", "done", "failed", "cancelled"]


@dataclass(frozen=True)
class Upload:
    """An uploaded file: its suffix (".c3d") and bytes, the input frame its labels start at
    (``start``: a relabel from a later frame), and the markers left out there (absent)."""

    suffix: str
    data: bytes
    start: int = 0
    absent: tuple[str, ...] = ()


class Base(DeclarativeBase):
    pass


class JobRow(Base):
    __tablename__ = "jobs"
    seq: Mapped[int] = mapped_column(primary_key=True, autoincrement=True)  # newest-first order
    id: Mapped[str] = mapped_column(String(32), unique=True)
    owner: Mapped[str] = mapped_column(String(200), index=True)
    state: Mapped[JobState] = mapped_column(String(16), index=True)  # typed only: stored as text
    source: Mapped[str] = mapped_column(String(300))
    created_at: Mapped[datetime]
    updated_at: Mapped[datetime]
    windows_total: Mapped[int]
    windows_done: Mapped[int] = mapped_column(default=0)
    error: Mapped[str | None] = mapped_column(Text)
    input: Mapped[bytes] = deferred(mapped_column(LargeBinary))  # stores made before ``InputRow``; empty since
    result: Mapped[bytes | None] = deferred(mapped_column(LargeBinary))  # LabeledTrajectories npz
    idempotency_key: Mapped[str | None] = mapped_column(String(200))  # the client's Idempotency-Key header


# One job per owner and key (rows without a key are not constrained: unique indexes allow many nulls).
IDEMPOTENCY_INDEX = Index("ix_jobs_owner_idempotency_key", JobRow.owner, JobRow.idempotency_key, unique=True)


class UploadRow(Base):
    """The file a job was uploaded as, kept so that its result is written as the CLI writes it:
    a C3D with the input's analog channels, events and parameters, any format numbered as
    the input (``service.io.recording.SourceFile``). Its own table: stores made before it
    get it from ``create_all``, and a capture-document job has none."""

    __tablename__ = "uploads"
    job_id: Mapped[str] = mapped_column(ForeignKey("jobs.id"), primary_key=True)
    suffix: Mapped[str] = mapped_column(String(8))
    data: Mapped[bytes] = deferred(mapped_column(LargeBinary))
    start: Mapped[int] = mapped_column(default=0)
    absent: Mapped[str] = mapped_column(Text, default="[]")  # JSON list of names


class InputRow(Base):
    """A job's validated capture document JSON. Its own table, not a column of ``jobs``: the
    job's row is updated once per window, and SQLite rewrites a row whole, so a 53 MB document
    made each window's count cost 127 ms (a 50,000-frame job spent 282 s against 59 s of
    labeling). Stores made before it keep their documents in ``jobs.input``, read from there."""

    __tablename__ = "job_inputs"
    job_id: Mapped[str] = mapped_column(ForeignKey("jobs.id"), primary_key=True)
    document: Mapped[bytes] = deferred(mapped_column(LargeBinary))


class WarningsRow(Base):
    """The lines a finished labeling warns of (``service.labeling.result_warnings``), as a
    JSON list: what ``markerflow track`` prints after its summary. Its own table, so stores
    made before it get it from ``create_all``; a job done before it has none."""

    __tablename__ = "job_warnings"
    job_id: Mapped[str] = mapped_column(ForeignKey("jobs.id"), primary_key=True)
    lines: Mapped[str] = mapped_column(Text)


class WindowRow(Base):
    __tablename__ = "windows"
    job_id: Mapped[str] = mapped_column(ForeignKey("jobs.id"), primary_key=True)
    index: Mapped[int] = mapped_column(primary_key=True)  # a window is stored at most once
    outcome: Mapped[bytes] = deferred(mapped_column(LargeBinary))
    stats: Mapped[str] = mapped_column(Text)  # WindowStats.to_dict() as JSON (gap may be Infinity)
    solve_seconds: Mapped[float]
    worker: Mapped[str] = mapped_column(String(200))  # host:pid that computed it
    finished_at: Mapped[datetime]


def _sqlite_pragmas(connection, _record) -> None:
    """WAL lets readers (status, events) run beside the writing job; FULL syncs every commit.

    ``synchronous=FULL`` rather than NORMAL: in WAL mode NORMAL survives a killed process
    but may lose the last commits on power loss, and a 202 promises the job is stored.
    One fsync per window is small beside a window's solve. ``busy_timeout`` lets Dask
    workers in other processes wait for the write lock instead of failing.
    """
    cursor = connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=FULL")
    cursor.execute("PRAGMA busy_timeout=30000")
    cursor.close()


def engine_for(url: str) -> Engine:
    """An engine with the tables created; SQLite gets its pragmas on every connection."""
    engine = create_engine(url)
    if engine.dialect.name == "sqlite":
        event.listen(engine, "connect", _sqlite_pragmas)
    Base.metadata.create_all(engine)
    _add_idempotency_key(engine)
    return engine


def _add_idempotency_key(engine: Engine) -> None:
    """A store made before ``jobs.idempotency_key`` existed gets the column (null) and its index.

    Standard SQL, for SQLite and PostgreSQL alike. Two processes opening an old store at
    once may both try: the loser's error is ignored once the column is there.
    """
    if _has_idempotency_key(engine):
        return
    try:
        with engine.begin() as connection:
            connection.execute(text("ALTER TABLE jobs ADD COLUMN idempotency_key VARCHAR(200)"))
    except DBAPIError:
        if not _has_idempotency_key(engine):
            raise
    IDEMPOTENCY_INDEX.create(engine, checkfirst=True)


def _has_idempotency_key(engine: Engine) -> bool:
    return "idempotency_key" in {column["name"] for column in inspect(engine).get_columns("jobs")}
