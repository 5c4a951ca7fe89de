"""A job's capture document lives beside its row, not in it.

The job's row is updated once per window (its count), and SQLite rewrites a row whole: with
the document in it, a 53 MB document made each window cost 127 ms, and a 50,000-frame job
spent 282 s where its windows took 59 s.
"""

from __future__ import annotations

import json
import sqlite3

from test_service_security import small_document

from service.server.store import store_for


def _document() -> bytes:
    return json.dumps({**small_document(frames=7), "window": 3}).encode()


def test_the_row_counted_per_window_does_not_hold_the_document(tmp_path):
    db = tmp_path / "jobs.db"
    store = store_for(f"sqlite:///{db}")
    job, _ = store.add("local", "json", _document(), 3)
    with sqlite3.connect(db) as connection:
        (held,) = connection.execute("SELECT length(input) FROM jobs WHERE id = ?", (job.id,)).fetchone()
    assert held == 0 and store.input(job.id) == _document()


def test_a_store_made_before_keeps_reading_its_documents_and_removes_them(tmp_path):
    db = tmp_path / "jobs.db"
    store = store_for(f"sqlite:///{db}")
    job, _ = store.add("local", "json", _document(), 3)
    with sqlite3.connect(db) as connection:  # as an older markerflow stored it
        connection.execute("UPDATE jobs SET input = ? WHERE id = ?", (_document(), job.id))
        connection.execute("DELETE FROM job_inputs")
    assert store.input(job.id) == _document()
    assert store.cancel(job.id) and store.remove(job.id)
    new, _ = store.add("local", "json", _document(), 3)
    assert store.cancel(new.id) and store.remove(new.id)
    with sqlite3.connect(db) as connection:
        assert connection.execute("SELECT count(*) FROM job_inputs").fetchone() == (0,)
