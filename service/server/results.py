"""A job's labeled trajectories: stored as npz, served as JSON, CSV or C3D.

The result is stored once, when the job finishes (not assembled on each fetch): in
camera mode assembling needs the cross-camera cloud, which is costly to rebuild. Only a
partial result (a job not done) is assembled on request, from its stored windows.
"""

from __future__ import annotations

import io
import json
import tempfile
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from service.capture.document import read_capture_document
from service.errors import InputError
from service.io.formats import kept_source, read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, Recording
from service.labeling.absent_markers import in_order, with_absent
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.outcome import WindowOutcome
from service.server.store import Job, JobStore
from service.server.tables import Upload

MEDIA_TYPES = {"json": "application/json", "csv": "text/csv; charset=utf-8", "c3d": "application/octet-stream"}


def trajectories_to_bytes(traj: LabeledTrajectories) -> bytes:
    """Exact, pickle-free bytes of ``traj`` (names and rate in a JSON header)."""
    buffer = io.BytesIO()
    header = json.dumps({"names": list(traj.names), "rate": float(traj.rate), "view_names": list(traj.view_names)})
    np.savez_compressed(buffer, header=np.array(header), positions=traj.positions, occluded=traj.occluded,
                        point_index=traj.point_index, filled=traj.filled, best_view=traj.best_view,
                        confidence=traj.confidence, unlabeled=traj.unlabeled)
    return buffer.getvalue()


def trajectories_from_bytes(data: bytes) -> LabeledTrajectories:
    with np.load(io.BytesIO(data), allow_pickle=False) as stored:
        header = json.loads(str(stored["header"]))
        return LabeledTrajectories(
            names=header["names"], positions=stored["positions"], occluded=stored["occluded"], rate=header["rate"],
            point_index=stored["point_index"], filled=stored["filled"],
            # results stored before best view existed have none
            best_view=stored["best_view"] if "best_view" in stored else np.zeros((0, 0), dtype=int),
            view_names=header.get("view_names", []),
            confidence=stored["confidence"] if "confidence" in stored else np.zeros((0, 0)),  # none stored before
            unlabeled=stored["unlabeled"] if "unlabeled" in stored else np.zeros((0, 0, 3)),  # none stored before
        )


def stored_windows_trajectories(document: bytes, outcomes: list[WindowOutcome]) -> LabeledTrajectories:
    """What the stored windows label (frame 0 and the windows' frames); later frames occluded."""
    capture = read_capture_document(document, "input")  # stored before a check was added: InputError, a 422
    return CaptureLabeling(capture.capture(), capture.options()).result(outcomes)


def nullable(values: np.ndarray) -> list[Any]:
    """Nested lists with None where NaN (JSON has no NaN)."""
    cells = values.astype(object)
    cells[np.isnan(values)] = None
    return cells.tolist()


def trajectories_json(traj: LabeledTrajectories) -> dict:
    """``positions`` ``[frame][marker] = [x, y, z]`` mm or null where occluded; ``filled`` the
    predicted position where occluded, null elsewhere; ``best_view`` ``[frame][marker]`` the
    name of the camera that shows the marker best (camera mode; null where the marker has no
    position), null for 3D points;
    ``confidence`` ``[frame][marker]`` the probability that the label is right
    (``service.labeling.confidence``, calibrated: ``formulations.confidence.calibration``),
    null where no window said."""
    return {
        "markers": list(traj.names), "rate": traj.rate, "positions": nullable(traj.positions),
        "occluded": traj.occluded.tolist(), "filled": nullable(traj.filled) if traj.filled.size else None,
        "best_view": traj.best_view_names(),
        "confidence": nullable(traj.confidence) if traj.confidence.size else None,
    }


def render(traj: LabeledTrajectories, format: str, upload: Upload | None = None) -> bytes:
    """The result file's bytes; CSV and C3D through ``write_labeled``, as the CLI writes them:
    from an ``upload``, in its unit and frame numbering (labels from its ``start``, the markers
    absent there written missing), and a C3D of a C3D is that file with only its points
    replaced (its analog channels, force plates, events and parameters kept)."""
    if format == "json":
        return json.dumps(trajectories_json(traj)).encode()
    with tempfile.TemporaryDirectory(prefix="markerflow-result-") as folder:
        path = Path(folder) / f"result.{format}"
        try:
            if upload is None:
                write_labeled(path, traj)
            else:
                recording = _recording(upload, Path(folder))
                whole = in_order(with_absent(traj, list(upload.absent)), recording.names)
                write_labeled(path, whole, kept_source(recording.source, whole.names)[0], upload.start)
        except InputError as error:  # the writers name their path: the caller sees only the file's name
            raise InputError(str(error).replace(str(path), path.name)) from None
        return path.read_bytes()


def _recording(upload: Upload, folder: Path) -> Recording:
    """The uploaded file, for its column order and what output keeps of it (``kept_source``).
    It was read whole, in a bounded child, when the job was accepted: reading it again is safe."""
    path = folder / f"upload{upload.suffix}"
    path.write_bytes(upload.data)
    return read_labeled(path)


def job_file(store: JobStore, job_id: str, format: str, done: bool) -> bytes:
    """A job's result file as the API and the page serve it: the stored result of a ``done``
    job, else what its stored windows label; from an uploaded file, written as its input."""
    traj = (trajectories_from_bytes(store.result(job_id)) if done
            else stored_windows_trajectories(store.input(job_id), store.outcomes(job_id)))
    return render(traj, format, store.upload(job_id))


def attachment(job: Job, format: str) -> str:
    """``Content-Disposition`` of a result download: named after the uploaded take
    (``walk_labeled-1a2b3c4d.c3d``; ``walk_labeled-1a2b3c4d-partial-failed.c3d`` before it is
    done), as every download was ``markerflow-<id>``; an ASCII
    name and the UTF-8 one (RFC 6266) for names beyond ASCII."""
    stem = Path(job.source).stem if job.source != "json" else "markerflow"
    # a job not done gives its stored windows only: named so, not as the whole result would be
    part = "" if job.state == "done" else f"-partial-{job.state}"
    name = f"{stem}_labeled-{job.id[:8]}{part}.{format}"
    ascii_name = "".join(c if c.isascii() and (c.isalnum() or c in "._-") else "_" for c in name)
    return f"attachment; filename=\"{ascii_name}\"; filename*=UTF-8''{quote(name)}"
