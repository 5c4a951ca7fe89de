"""Back-pressure and retries: a full queue answers 429 with Retry-After; a retried POST with the
same Idempotency-Key gets the job the first POST made; a store from before the key still opens."""

from __future__ import annotations

import json
import sqlite3
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from service_fixtures import serving
from test_service_security import ALICE, BOB, JSON, as_, small_document

from service.server.settings import Settings
from service.server.store import store_for

DOCUMENT = json.dumps(small_document())
DATA_C3D = Path(__file__).resolve().parents[2] / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


@pytest.fixture()
def guarded(tmp_path):
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    with serving(Settings(db=db, tokens={"alice": ALICE, "bob": BOB}, max_queued_jobs=3, retry_after_seconds=7)) as client:
        yield client, store_for(Settings(db=db).db)


def _post(client, token: str, key: str | None = None, body: str = DOCUMENT):
    headers = {**JSON, **as_(token), **({"Idempotency-Key": key} if key else {})}
    return client.post("/v1/jobs", content=body, headers=headers)


def test_a_full_queue_answers_429_with_retry_after(guarded):
    client, store = guarded
    # Jobs put in the store directly are never handed to the executor: they stay queued.
    for _ in range(3):
        store.add("carol", "json", DOCUMENT.encode(), 1)
    refused = _post(client, ALICE)
    assert refused.status_code == 429 and refused.headers["retry-after"] == "7"
    assert refused.json() == {"message": "3 jobs are queued, the limit (max_queued_jobs); retry later"}
    assert store.queued() == 3  # nothing was added


def test_the_same_idempotency_key_returns_the_same_job(guarded):
    client, store = guarded
    first = _post(client, ALICE, key="take-42")
    assert first.status_code == 202
    again = _post(client, ALICE, key="take-42")
    assert again.status_code == 202 and again.json()["id"] == first.json()["id"]
    assert again.headers["location"] == f"/v1/jobs/{first.json()['id']}"
    # Another owner's key is its own; another key is another job.
    assert _post(client, BOB, key="take-42").json()["id"] != first.json()["id"]
    assert _post(client, ALICE, key="take-43").json()["id"] != first.json()["id"]
    listed = client.get("/v1/jobs", headers=as_(ALICE)).json()
    assert listed["total"] == 2


def test_a_key_reused_for_another_capture_is_422(guarded):
    """The second capture was answered 202 with the first's job, and never labeled."""
    client, _ = guarded
    first = _post(client, ALICE, key="take-44")
    other = json.dumps({**small_document(), "window": 3})
    reused = _post(client, ALICE, key="take-44", body=other)
    assert reused.status_code == 422, reused.text
    assert reused.json()["message"].startswith(f"Idempotency-Key: already used for another capture (job {first.json()['id']})")


def test_concurrent_posts_of_two_captures_under_one_key_make_one_job_for_one_capture(guarded):
    """Posted at once, each found no job under the key; the ones whose insert lost the race
    were answered 202 with the winner's job, whatever capture they carried."""
    client, _ = guarded
    bodies = [DOCUMENT, json.dumps({**small_document(), "window": 3})] * 4
    with ThreadPoolExecutor(len(bodies)) as pool:
        answers = list(pool.map(lambda body: _post(client, ALICE, key="take-45", body=body), bodies))
    accepted = {(answer.json()["id"], body) for answer, body in zip(answers, bodies) if answer.status_code == 202}
    assert len(accepted) == 1, accepted  # one job, answered only to the capture it holds
    refused = [answer for answer in answers if answer.status_code != 202]
    assert len(refused) == 4 and all(a.status_code == 422 and "another capture" in a.json()["message"] for a in refused)


def test_a_field_sent_twice_is_422(guarded):
    client, _ = guarded
    upload = DATA_C3D.read_bytes()
    answer = client.post("/v1/jobs", headers=as_(ALICE), files={"file": ("take.c3d", upload)},
                         data={"window": ["10", "50"]})
    assert answer.status_code == 422 and answer.json()["message"] == "window: given 2 times; send each field once"


def test_a_retry_is_answered_even_with_the_queue_full(guarded):
    client, store = guarded
    first = _post(client, ALICE, key="before-full")
    for _ in range(3):
        store.add("carol", "json", DOCUMENT.encode(), 1)
    assert _post(client, ALICE, key="before-full").json()["id"] == first.json()["id"]
    assert _post(client, ALICE, key="after-full").status_code == 429


def test_an_unprintable_or_long_key_is_422(guarded):
    client, _ = guarded
    for key in ("a b", "x" * 201):
        answer = _post(client, ALICE, key=key)
        assert answer.status_code == 422 and answer.json()["message"].startswith("header.Idempotency-Key:")


def test_a_store_from_before_the_key_opens_and_takes_keys(tmp_path):
    path = tmp_path / "old.db"
    with sqlite3.connect(path) as old:  # the jobs table as the previous version made it
        old.execute("CREATE TABLE jobs (seq INTEGER PRIMARY KEY, id VARCHAR(32) UNIQUE, owner VARCHAR(200), "
                    "state VARCHAR(16), source VARCHAR(300), created_at DATETIME, updated_at DATETIME, "
                    "windows_total INTEGER, windows_done INTEGER, error TEXT, input BLOB, result BLOB)")
        old.execute("INSERT INTO jobs VALUES (1, 'a' || hex(randomblob(15)), 'local', 'done', 'json', "
                    "'2026-01-01 00:00:00', '2026-01-01 00:00:00', 1, 1, NULL, x'7b7d', NULL)")
    store = store_for(f"sqlite:///{path}")
    job, new = store.add("local", "json", b"{}", 1, key="k")
    assert new and store.add("local", "json", b"{}", 1, key="k") == (job, False)
    assert store.page("local", 10, 0)[1] == 2
