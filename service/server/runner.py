"""Run or resume one stored job: the code path of the job worker processes and of Dask workers.

Each finished window is committed (outcome + stats + count) before the next is computed,
so a restart resumes after the last stored window and recomputes nothing: the library
guarantees ``windows(after=last)`` gives what an uninterrupted run would. Windows stored by
a markerflow with another marker state (upgraded while the job was queued or running) are
dropped and the job relabels from its start: the result is this version's, never a mix.

Once every window is stored, a second pass may label the take again
(``service.labeling.second_pass``); if it is kept, its windows replace the stored ones in the
transaction that stores the result, and a restart before that refines the stored first pass
again.

A window that raises fails the job with the window's index and message; the windows
stored before it stay, and ``GET /v1/jobs/{id}/result?partial=true`` assembles them. The store
failing (a database restart, a full disk) does not fail the job, which could not be recorded
anyway: the error goes up, and the executor runs the job again once the store answers.
"""

from __future__ import annotations

import logging
import os
import socket
from collections.abc import Callable

from sqlalchemy.exc import OperationalError

from service.capture.document import read_capture_document
from service.errors import InputError
from service.labeling.absent_markers import absent_warning
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.outcome import StaleOutcome, WindowOutcome
from service.server.results import trajectories_to_bytes
from service.server.store import JobStore, WindowTaken, store_for

log = logging.getLogger("markerflow.server")


def run_job(db_url: str, job_id: str, stop: Callable[[], bool] = lambda: False) -> str:
    """Label the job's remaining windows and store the result; returns the job's state.

    Args:
        db_url: The store's URL (a Dask worker opens its own connection from it).
        job_id: The job.
        stop: Asked between windows; True leaves the job ``running``, to resume on restart.
    """
    store = store_for(db_url)
    worker = f"{socket.gethostname()}:{os.getpid()}"  # which process computed each window
    if not store.start(job_id):
        return store.known(job_id).state
    where = ""  # "window k: " once the windows are being computed
    try:
        document = read_capture_document(store.input(job_id), "input")  # stored before a check was added: InputError
        capture = document.capture()
        labeling = CaptureLabeling(capture, document.options())
        outcomes = _resumable_outcomes(store, job_id)
        where = f"window {len(outcomes)}: "
        for outcome in labeling.windows(after=outcomes[-1] if outcomes else None):
            if not store.save_window(job_id, outcome, worker):  # cancelled while the window ran
                return store.known(job_id).state
            outcomes.append(outcome)
            where = f"window {len(outcomes)}: " if len(outcomes) < labeling.n_windows else ""
            # Between windows: a cancel (from any process) or a shutdown stops the job here.
            if stop() or store.known(job_id).state != "running":
                return store.known(job_id).state
        kept = labeling.refine(outcomes, _second_pass_note(store, job_id),
                               stop=lambda: stop() or store.known(job_id).state != "running")
        if kept is None:
            return store.known(job_id).state
        # The kept windows replace the stored ones with the result, in one transaction: a
        # restart then finds either the first pass (and refines it again) or a finished job.
        result = labeling.result(kept)
        upload = store.upload(job_id)  # frames numbered as the file's, from its start, as track says them
        start, unit = (upload.start, "the file's unit") if upload is not None else (0, "mm")
        absent = absent_warning(list(upload.absent), upload.start) if upload is not None else None
        store.finish(job_id, trajectories_to_bytes(result), None if kept is outcomes else (kept, worker),
                     labeling.warnings(result, [o.stats for o in kept], unit, start) + ([absent] if absent else []))
    except WindowTaken as taken:
        log.warning("%s; another runner has the job", taken)
    except OperationalError:  # the store itself (down, disk full): the job is retried, not failed by it
        raise
    except InputError as error:  # e.g. a formulation that cannot take one of the windows
        store.fail(job_id, f"{where}{error}")
    except Exception as error:  # a bug: the job fails with its name, the server keeps serving
        log.exception("job %s failed", job_id)
        first_line = next(iter(str(error).splitlines()), "")  # the job's error is one line, like every message
        store.fail(job_id, f"{where}internal error: {type(error).__name__}: {first_line}")
    return store.known(job_id).state


def _resumable_outcomes(store: JobStore, job_id: str) -> list[WindowOutcome]:
    """The job's stored windows to resume after; none (the job relabels from its start) when
    they were stored by a markerflow whose marker state differs (an upgrade mid-job)."""
    try:
        return store.outcomes(job_id)
    except StaleOutcome as stale:
        log.warning("job %s: %s; relabeling from the first window", job_id, stale)
        store.forget_windows(job_id)
        return []


def _second_pass_note(store: JobStore, job_id: str) -> Callable[[int, int], None]:
    """The second pass's progress as the job's running note (``JobStore.note``)."""
    def note(done: int, total: int) -> None:
        store.note(job_id, f"second pass: {done} of {total} windows (the first pass is done; the pass whose rigid "
                           "pairs fit the first frame better is kept, then a frame-by-frame reading where it fits better)")
    return note
