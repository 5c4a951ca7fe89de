"""A job whose stored windows an older markerflow wrote (an upgrade while it was queued or
running) relabels from its start instead of failing on the missing marker state."""

from __future__ import annotations

import io
import sqlite3

import numpy as np
import pytest
from service_fixtures import document_json, generated_capture

from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.outcome import StaleOutcome, WindowOutcome
from service.server.results import trajectories_from_bytes
from service.server.runner import run_job
from service.server.store import store_for

OPTIONS = LabelingOptions(window=10)


def _as_older_version(outcome: WindowOutcome) -> bytes:
    """``outcome``'s bytes without the state's burst fields, and every label moved to -1:
    resuming from it would show in the result."""
    with np.load(io.BytesIO(outcome.to_bytes()), allow_pickle=False) as stored:
        arrays = {k: stored[k] for k in stored.files if k not in ("state.burst_var", "state.last_residual")}
    arrays["point_index"] = np.full_like(arrays["point_index"], -1)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()


def test_an_outcome_without_a_state_field_is_stale_not_a_key_error():
    outcome = next(CaptureLabeling(generated_capture(frames=30, seed=5), OPTIONS).windows())
    with pytest.raises(StaleOutcome, match="window 0 was stored without marker state burst_var, last_residual"):
        WindowOutcome.from_bytes(_as_older_version(outcome))


def test_a_job_with_windows_of_an_older_version_relabels_and_finishes(tmp_path):
    capture = generated_capture(frames=60, seed=5)
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    labeling = CaptureLabeling(capture, OPTIONS)
    store = store_for(db)
    job, _ = store.add("local", "json", document_json(capture, OPTIONS).encode(), labeling.n_windows)
    older = list(labeling.windows())[:2]
    assert store.start(job.id)  # the older version had started it: windows are stored while running
    for outcome in older:
        assert store.save_window(job.id, outcome, "older")
    with sqlite3.connect(tmp_path / "jobs.db") as connection:
        for outcome in older:
            connection.execute("UPDATE windows SET outcome = ? WHERE job_id = ? AND \"index\" = ?",
                               (_as_older_version(outcome), job.id, outcome.index))

    assert run_job(db, job.id) == "done"
    expected, _ = CaptureLabeling(capture, OPTIONS).label()
    result = trajectories_from_bytes(store.result(job.id))
    assert np.array_equal(result.occluded, expected.occluded)
    assert np.array_equal(result.positions, expected.positions, equal_nan=True)
    assert store.known(job.id).windows_done == labeling.n_windows
    assert {w.worker for w in store.windows(job.id)} != {"older"}
