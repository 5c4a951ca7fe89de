"""The job store: jobs, their inputs, every finished window and the final result, in SQL.

Any SQLAlchemy URL works (``postgresql+psycopg://...``); a SQLite file is the embedded
default. Each state change is one short transaction, so a process killed at any instant
leaves the store at the last committed step: a job accepted (202) is in it with its
input, and a window is either wholly stored (outcome, stats, ``windows_done``) or absent.
"""

from __future__ import annotations

import json
import uuid
from dataclasses import dataclass
from datetime import UTC, datetime
from functools import cache
from typing import Any, cast, get_args

from sqlalchemy import delete, func, select, update
from sqlalchemy.engine import CursorResult
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import sessionmaker

from service.labeling.outcome import WindowOutcome
from service.server.tables import InputRow, JobRow, JobState, Upload, UploadRow, WarningsRow, WindowRow, engine_for

ACTIVE: tuple[JobState, ...] = ("queued", "running")
STATES: tuple[JobState, ...] = get_args(JobState)


@dataclass(frozen=True)
class Job:
    """A job as the API shows it (input and result stay in the store)."""

    id: str
    owner: str
    state: JobState
    source: str
    created_at: datetime
    updated_at: datetime
    windows_total: int
    windows_done: int
    error: str | None

    @classmethod
    def of(cls, row: JobRow) -> Job:
        return cls(row.id, row.owner, row.state, row.source, _utc(row.created_at), _utc(row.updated_at),
                   row.windows_total, row.windows_done, row.error)


@dataclass(frozen=True)
class StoredWindow:
    index: int
    stats: dict
    worker: str


class WindowTaken(Exception):
    """Another runner stored this window first (a job resumed twice): this runner stops."""


def _now() -> datetime:
    return datetime.now(UTC)


def _utc(moment: datetime) -> datetime:
    """SQLite hands back naive datetimes; every stored time is UTC."""
    return moment if moment.tzinfo else moment.replace(tzinfo=UTC)


@cache
def store_for(url: str) -> JobStore:
    """One store (one connection pool) per database URL per process."""
    return JobStore(url)


class JobStore:
    """Jobs and their windows, one transaction per step.

    Args:
        url: SQLAlchemy database URL.
    """

    def __init__(self, url: str) -> None:
        self.engine = engine_for(url)
        self.session = sessionmaker(self.engine, expire_on_commit=False)

    def add(self, owner: str, source: str, document: bytes, windows_total: int,
            key: str | None = None, upload: Upload | None = None) -> tuple[Job, bool]:
        """A new queued job and True; with an idempotency ``key`` the owner already used, that
        job and False. ``upload``: the file the document was read from, kept for its output."""
        now = _now()
        row = JobRow(id=uuid.uuid4().hex, owner=owner, state="queued", source=source[:300], created_at=now,
                     updated_at=now, windows_total=windows_total, windows_done=0, input=b"",
                     idempotency_key=key)
        try:
            with self.session.begin() as session:
                session.add(row)
                session.flush()  # the job row first: the input's and upload's keys refer to it
                session.add(InputRow(job_id=row.id, document=document))
                if upload is not None:
                    session.add(UploadRow(job_id=row.id, suffix=upload.suffix, data=upload.data, start=upload.start,
                                          absent=json.dumps(list(upload.absent))))
        except IntegrityError:
            earlier = self.by_key(owner, key) if key is not None else None
            if earlier is None:  # not the key's unique index: a real conflict
                raise
            return earlier, False
        return Job.of(row), True

    def by_key(self, owner: str, key: str) -> Job | None:
        """The owner's job submitted with Idempotency-Key ``key``, if any."""
        with self.session() as session:
            row = session.scalars(select(JobRow).where(JobRow.owner == owner, JobRow.idempotency_key == key)).first()
            return Job.of(row) if row else None

    def queued(self) -> int:
        """Jobs waiting for a runner, over all owners."""
        with self.session() as session:
            return session.execute(select(func.count()).select_from(JobRow).where(JobRow.state == "queued")).scalar_one()

    def intake(self, owner: str, key: str | None) -> tuple[Job | None, int]:
        """What a submission needs to know first, in one call: the job the owner already made
        with ``key`` (None if none, or no key), and how many jobs are queued."""
        return self.by_key(owner, key) if key is not None else None, self.queued()

    def get(self, job_id: str, owner: str | None = None) -> Job | None:
        """The job, or None if it does not exist or belongs to another owner."""
        query = select(JobRow).where(JobRow.id == job_id)
        if owner is not None:
            query = query.where(JobRow.owner == owner)
        with self.session() as session:
            row = session.scalars(query).first()
            return Job.of(row) if row else None

    def known(self, job_id: str) -> Job:
        """A job known to exist (an active job cannot be removed), e.g. one a runner follows."""
        with self.session() as session:
            return Job.of(session.execute(select(JobRow).where(JobRow.id == job_id)).scalar_one())

    def page(self, owner: str, limit: int, offset: int, state: JobState | None = None) -> tuple[list[Job], int]:
        """The owner's jobs (in ``state``, if given), newest first, and how many there are."""
        chosen = [JobRow.owner == owner] + ([JobRow.state == state] if state is not None else [])
        with self.session() as session:
            rows = session.scalars(
                select(JobRow).where(*chosen).order_by(JobRow.seq.desc()).limit(limit).offset(offset)
            ).all()
            total = session.execute(select(func.count()).select_from(JobRow).where(*chosen)).scalar_one()
            return [Job.of(row) for row in rows], total

    def unfinished(self) -> list[str]:
        with self.session() as session:
            return list(session.scalars(select(JobRow.id).where(JobRow.state.in_(ACTIVE)).order_by(JobRow.seq)))

    def input(self, job_id: str) -> bytes:
        with self.session() as session:
            document = session.execute(select(InputRow.document).where(InputRow.job_id == job_id)).scalar()
            return document if document is not None else session.execute(
                select(JobRow.input).where(JobRow.id == job_id)).scalar_one()

    def upload(self, job_id: str) -> Upload | None:
        """The file the job was uploaded as; None for a capture document."""
        with self.session() as session:
            row = session.execute(select(UploadRow.suffix, UploadRow.data, UploadRow.start, UploadRow.absent)
                                  .where(UploadRow.job_id == job_id)).first()
        return None if row is None else Upload(row[0], row[1], row[2], tuple(json.loads(row[3])))

    def upload_start(self, job_id: str) -> int | None:
        """The take's frame an uploaded job's frame 0 is (``--start``); None for a capture document."""
        with self.session() as session:
            return session.execute(select(UploadRow.start).where(UploadRow.job_id == job_id)).scalar()

    def uploaded(self, job_id: str) -> bool:
        """Whether the job came as a file (without reading the file)."""
        with self.session() as session:
            return session.execute(select(UploadRow.job_id).where(UploadRow.job_id == job_id)).first() is not None

    def result(self, job_id: str) -> bytes:
        """The result of a done job (``finish`` stores it with the state)."""
        with self.session() as session:
            stored = session.execute(select(JobRow.result).where(JobRow.id == job_id)).scalar_one()
        if stored is None:
            raise LookupError(f"job {job_id} has no result")
        return stored

    def outcomes(self, job_id: str) -> list[WindowOutcome]:
        with self.session() as session:
            stored = session.scalars(select(WindowRow.outcome).where(WindowRow.job_id == job_id).order_by(WindowRow.index))
            return [WindowOutcome.from_bytes(data) for data in stored]

    def windows(self, job_id: str, after: int = -1) -> list[StoredWindow]:
        """Stored windows with index > ``after``, in order."""
        query = (select(WindowRow.index, WindowRow.stats, WindowRow.worker)
                 .where(WindowRow.job_id == job_id, WindowRow.index > after).order_by(WindowRow.index))
        with self.session() as session:
            return [StoredWindow(i, json.loads(stats), worker) for i, stats, worker in session.execute(query)]

    def start(self, job_id: str) -> bool:
        """Mark the job running; False if it is no longer queued or running (cancelled, finished).
        A running note (``note``) left by a runner that died goes: the job read "second pass: 58
        of 58 windows" until this runner's pass counted again from 0."""
        started = self._move(job_id, ACTIVE, state="running")
        if started:
            with self.session.begin() as session:
                session.execute(delete(WarningsRow).where(WarningsRow.job_id == job_id))
        return started

    def save_window(self, job_id: str, outcome: WindowOutcome, worker: str) -> bool:
        """Store one finished window and count it, in one transaction; False (nothing stored)
        when the job is no longer running: a cancel answered with its count of windows, and a
        window finished after it must not change what it said.

        Raises:
            WindowTaken: The window is already stored.
        """
        try:
            with self.session.begin() as session:
                counted = session.execute(update(JobRow).where(JobRow.id == job_id, JobRow.state == "running")
                                          .values(windows_done=outcome.index + 1, updated_at=_now()))
                if cast(CursorResult[Any], counted).rowcount != 1:
                    raise _NotRunning  # leaving the block rolls the transaction back
                session.add(_window_row(job_id, outcome, worker))
        except _NotRunning:
            return False
        except IntegrityError:
            raise WindowTaken(f"job {job_id} window {outcome.index} is already stored") from None
        return True

    def forget_windows(self, job_id: str) -> None:
        """Drop the job's stored windows (they cannot be resumed from: ``StaleOutcome``)."""
        with self.session.begin() as session:
            session.execute(delete(WindowRow).where(WindowRow.job_id == job_id))
            session.execute(update(JobRow).where(JobRow.id == job_id).values(windows_done=0, updated_at=_now()))

    def finish(self, job_id: str, result: bytes, windows: tuple[list[WindowOutcome], str] | None = None,
               warnings: list[str] | None = None) -> bool:
        """Store the result of a running job and what it warns of; ``windows`` (outcomes,
        worker) replace its stored windows in the same transaction (a second pass kept), so a
        restart never sees a mix."""
        with self.session.begin() as session:
            moved = session.execute(update(JobRow).where(JobRow.id == job_id, JobRow.state == "running")
                                    .values(updated_at=_now(), state="done", result=result))
            if cast(CursorResult[Any], moved).rowcount != 1:
                return False
            if windows is not None:
                session.execute(delete(WindowRow).where(WindowRow.job_id == job_id))
                session.add_all([_window_row(job_id, outcome, windows[1]) for outcome in windows[0]])
            session.execute(delete(WarningsRow).where(WarningsRow.job_id == job_id))  # a running note (``note``)
            if warnings:
                session.add(WarningsRow(job_id=job_id, lines=json.dumps(warnings)))
            return True

    def note(self, job_id: str, line: str) -> None:
        """What a running job is doing past its windows (its second pass), shown as its warning
        until it is done: the progress stood at N/N for as long as the first pass took."""
        with self.session.begin() as session:
            session.merge(WarningsRow(job_id=job_id, lines=json.dumps([line])))

    def warnings(self, job_id: str) -> list[str]:
        """What the finished labeling warns of; while it runs, its ``note`` if any."""
        with self.session() as session:
            lines = session.execute(select(WarningsRow.lines).where(WarningsRow.job_id == job_id)).scalar()
        return [] if lines is None else [str(line) for line in json.loads(lines)]

    def fail(self, job_id: str, error: str) -> bool:
        """A queued job fails too: its executor may give up before it starts (a lost Dask worker)."""
        return self._move(job_id, ACTIVE, state="failed", error=error)

    def cancel(self, job_id: str) -> bool:
        return self._move(job_id, ACTIVE, state="cancelled")

    def remove(self, job_id: str) -> bool:
        """Delete a finished job with its input, upload, windows, warnings and result: the
        store otherwise only grows (135_02 keeps about 27 MB, 8 times its C3D). False when the
        job is queued or running (cancel it first) or gone."""
        with self.session.begin() as session:
            gone = session.execute(delete(JobRow).where(JobRow.id == job_id, JobRow.state.not_in(ACTIVE)))
            if cast(CursorResult[Any], gone).rowcount != 1:
                return False
            for table in (WindowRow, UploadRow, WarningsRow, InputRow):
                session.execute(delete(table).where(table.job_id == job_id))
            return True

    def _move(self, job_id: str, allowed: tuple[JobState, ...], **values: Any) -> bool:
        """Change the job only if its state is in ``allowed``: a cancel is never overwritten."""
        with self.session.begin() as session:
            moved = session.execute(
                update(JobRow).where(JobRow.id == job_id, JobRow.state.in_(allowed)).values(updated_at=_now(), **values)
            )
            # Session.execute is typed as returning a Result; an UPDATE's result is a CursorResult.
            return cast(CursorResult[Any], moved).rowcount == 1


class _NotRunning(Exception):
    """Inside ``save_window``: the job stopped running, store nothing."""


def _window_row(job_id: str, outcome: WindowOutcome, worker: str) -> WindowRow:
    return WindowRow(job_id=job_id, index=outcome.index, outcome=outcome.to_bytes(),
                     stats=json.dumps(outcome.stats.to_dict()), solve_seconds=outcome.stats.solve_seconds,
                     worker=worker, finished_at=_now())
