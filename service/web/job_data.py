"""What a page shows of a job, read from the store: its options, certificates, labels and doubt.

The store keeps a job's input and result as bytes; the figures the pages need are derived
here. Inputs and finished results never change, so what is derived from them is cached per
job (``functools.lru_cache``), and a list of fifty jobs does not parse fifty inputs per view.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from service.capture.document import CaptureDocument
from service.io.recording import LabeledTrajectories
from service.labeling.stats import REPORTED_DOUBTFUL_BELOW, WindowStats, certificate_figures, reported_doubtful
from service.server.results import stored_windows_trajectories, trajectories_from_bytes
from service.server.store import Job, JobStore, StoredWindow, store_for
from service.server.submission import labeling_warnings

CACHED_JOBS = 256
CACHED_ENDED = 16  # failed or cancelled jobs' labels: assembled from windows, often long takes cut short


@dataclass(frozen=True)
class JobOptions:
    """How the job was asked to label, and what it was given."""

    formulation: str
    window: int
    association: str | None  # None for 3D points
    markers: int | None  # None: the subject model's markers
    frames: int
    model: bool = False  # a subject model came with the capture
    warnings: tuple[str, ...] = ()  # what the labeled frame says of the subject model sent with it


@dataclass(frozen=True)
class Labels:
    """A job's labels, with which of them are doubtful.

    ``doubt_source`` says what ``doubtful`` is, for the page to show.
    """

    names: list[str]
    rate: float
    positions: np.ndarray  # (F, M, 3), NaN where occluded
    occluded: np.ndarray  # (F, M) bool
    filled: np.ndarray  # (F, M) bool: occluded with a predicted position
    doubtful: np.ndarray  # (F, M) bool, seen labels only
    doubt_source: str
    best_view: list[list[str | None]] | None  # [frame][marker] camera, where the result names one
    first_frame: int = 0  # the take's frame number of frame 0: an upload's start, as warnings count frames

    def doubtful_share(self) -> float | None:
        """Doubtful labels / labels of these labels (what a done job's warning line counts); None with no label."""
        seen = int((~self.occluded).sum())
        return int(self.doubtful.sum()) / seen if seen else None


def options_of(document: bytes) -> JobOptions:
    """The options of a stored capture document (JSON, as ``CaptureDocument`` wrote it)."""
    fields = json.loads(document)
    formulation = fields["formulation"]
    cameras = fields.get("detections") is not None
    frames = next(iter(fields["detections"].values()), []) if cameras else fields["points"]
    return JobOptions(formulation=formulation_text(formulation),
                      window=fields["window"], association=fields["association"] if cameras else None,
                      markers=len(fields["markers"]) if fields.get("markers") is not None else None, frames=len(frames),
                      model=fields.get("model") is not None, warnings=_model_warnings(fields))


def formulation_text(formulation: str | dict) -> str:
    """A document's formulation as a user reads it: ``ilp (time_limit 5)`` for
    ``{"name": "ilp", "time_limit": 5}`` (the page showed that JSON, quotes escaped)."""
    if isinstance(formulation, str):
        return formulation
    parameters = ", ".join(f"{key} {json.dumps(value)}" for key, value in formulation.items() if key != "name")
    return f"{formulation['name']}{f' ({parameters})' if parameters else ''}"


def _model_warnings(fields: dict) -> tuple[str, ...]:
    """The warnings ``POST /v1/jobs`` answered, for a document with a model and labels (checked
    again on its first two frames, as the submission was)."""
    if fields.get("model") is None or not fields.get("markers"):
        return ()
    return labeling_warnings(CaptureDocument.model_validate({**fields, "points": fields["points"][:2]}))


@lru_cache(maxsize=CACHED_JOBS)
def job_options(db: str, job_id: str) -> JobOptions:
    return options_of(store_for(db).input(job_id))


def window_stats(windows: list[StoredWindow]) -> list[WindowStats]:
    return [WindowStats(**window.stats) for window in windows]


def labels_of(traj: LabeledTrajectories) -> Labels:
    """The labels of ``traj``, doubtful where their confidence is below ``REPORTED_DOUBTFUL_BELOW``
    (none are marked when the result carries no confidence), with each marker's best view
    per frame where the result names one (camera mode)."""
    occluded = np.asarray(traj.occluded, dtype=bool)
    filled = ~np.isnan(traj.filled).any(axis=2) & occluded if traj.filled.size else np.zeros_like(occluded)
    if traj.confidence.size:
        doubtful, source = reported_doubtful(traj.confidence, occluded), f"confidence below {REPORTED_DOUBTFUL_BELOW:.3g}"
    else:
        doubtful, source = np.zeros_like(occluded), "this result carries no per-label confidence"
    best_view = traj.best_view_names() if traj.best_view.size else None
    return Labels(list(traj.names), float(traj.rate), traj.positions, occluded, filled, doubtful, source, best_view)


@lru_cache(maxsize=CACHED_JOBS)
def finished_labels(db: str, job_id: str) -> Labels:
    """A done job's labels (its result and windows never change again)."""
    return labels_of(trajectories_from_bytes(store_for(db).result(job_id)))


@lru_cache(maxsize=CACHED_ENDED)
def ended_labels(db: str, job_id: str, windows_done: int) -> Labels:
    """A failed or cancelled job's labels from its stored windows, which no runner adds to
    again: assembled once, not on every view (38,250 frames took 30-40 s per page and plot)."""
    store = store_for(db)
    return labels_of(stored_windows_trajectories(store.input(job_id), store.outcomes(job_id)))


def job_labels(db: str, job: Job) -> Labels | None:
    """The labels so far: a done job's result; a failed or cancelled job's stored windows;
    None while it runs (assembling needs the whole cross-camera cloud in camera mode)."""
    store = store_for(db)
    if job.state == "done":
        labels = finished_labels(db, job.id)
    elif job.state in ("queued", "running") or job.windows_done == 0:
        return None
    else:
        labels = ended_labels(db, job.id, job.windows_done)
    return replace(labels, first_frame=store.upload_start(job.id) or 0)


def doubtful_share(windows: list[StoredWindow]) -> float | None:
    """Doubtful labels / labels over the stored windows; None where they counted no label
    (windows stored before labels had a confidence)."""
    stats = window_stats(windows)
    labels = sum(w.labels for w in stats)
    return sum(w.doubtful for w in stats) / labels if labels else None


def certificate_summary(windows: list[StoredWindow]) -> dict[str, float | None]:
    """``certificate_figures`` of the stored windows (integral share, gap median and max)."""
    return certificate_figures(window_stats(windows))


def capture_document(store: JobStore, job_id: str) -> CaptureDocument:
    return CaptureDocument.model_validate_json(store.input(job_id))
