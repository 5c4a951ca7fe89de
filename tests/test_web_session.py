"""The page's session cookie over real HTTP: set only for a valid token, HttpOnly and
SameSite=Strict, read by the page routes only (never by /v1), refused from another origin,
and checked before an upload's body is read; a C3D uploads through the page as through the API."""

from __future__ import annotations

from pathlib import Path

import httpx
import numpy as np
import pytest
from service_fixtures import document_json, generated_capture, serving, wait_for

from service.capture.capture import LabelingOptions
from service.evaluation.scene import generate_scene
from service.io.formats import write_labeled
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.spans import window_spans
from service.labeling.stats import doubtful_fraction
from service.server.settings import Settings
from service.web.session import COOKIE

ALICE = "alice-token-0123456789"


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    db = tmp_path_factory.mktemp("web-session") / "jobs.db"
    with serving(Settings(db=f"sqlite:///{db}", tokens={"alice": ALICE})) as client:
        yield client.base_url


@pytest.fixture
def client(server):
    """A client without cookies (httpx keeps what a response sets)."""
    with httpx.Client(base_url=server, timeout=60) as client:
        yield client


def _signed_in(client: httpx.Client) -> httpx.Client:
    answer = client.post("/session", headers={"Authorization": f"Bearer {ALICE}"})
    assert answer.status_code == 204 and client.cookies[COOKIE] == ALICE
    return client


def test_the_cookie_is_set_only_for_a_valid_token_and_kept_from_scripts_and_other_sites(client):
    assert client.post("/session", headers={"Authorization": "Bearer not-a-token-at-all"}).status_code == 401
    assert client.post("/session").status_code == 401
    answer = client.post("/session", headers={"Authorization": f"Bearer {ALICE}"})
    flags = [part.strip().lower() for part in answer.headers["set-cookie"].split(";")]
    assert flags[0] == f"{COOKIE}={ALICE}".lower()
    assert "httponly" in flags and "samesite=strict" in flags and "path=/" in flags
    assert not any(flag.startswith(("expires", "max-age")) for flag in flags)  # a browser-session cookie


def test_the_api_never_reads_the_cookie(client):
    browser = _signed_in(client)
    assert browser.get("/").status_code == 200
    assert browser.get("/v1/jobs").status_code == 401
    assert browser.post("/v1/jobs", content=b"{}", headers={"content-type": "application/json"}).status_code == 401


def test_pages_without_a_cookie_ask_for_the_token(client):
    assert client.get("/").status_code == 401 and "Sign in" in client.get("/").text
    assert "Sign out" not in client.get("/").text  # nothing to sign out of yet
    assert client.get("/jobs/" + "0" * 32).status_code == 401
    assert client.get("/jobs/" + "0" * 32 + "/plots/certificate.svg").status_code == 401


def test_an_upload_is_refused_before_its_body_without_a_cookie_or_from_another_origin(client):
    document = document_json(generated_capture(frames=10, seed=1))
    anonymous = client.post("/jobs", files={"file": ("take.json", document)})
    assert anonymous.status_code == 401 and anonymous.headers["connection"] == "close"
    browser = _signed_in(client)
    forged = browser.post("/jobs", files={"file": ("take.json", document)}, headers={"Origin": "http://evil.example"})
    assert forged.status_code == 403
    accepted = browser.post("/jobs", files={"file": ("take.json", document)}, data={"window": "5"},
                            headers={"Origin": str(client.base_url).rstrip("/")})
    assert accepted.status_code == 303 and accepted.headers["location"].startswith("/jobs/")


def test_without_tokens_the_pages_need_no_sign_in(tmp_path):
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}")) as local:
        page = local.get("/")
        assert page.status_code == 200 and "Label a capture" in page.text and "Sign out" not in page.text


def test_a_labeled_c3d_uploads_through_the_page_as_through_the_api(client, tmp_path):
    truth = generate_scene(n_frames=12, seed=2)
    write_labeled(tmp_path / "take.c3d", LabeledTrajectories(truth.names, truth.positions,
                                                             np.zeros(truth.positions.shape[:2], dtype=bool), truth.rate))
    browser = _signed_in(client)
    with (tmp_path / "take.c3d").open("rb") as upload:
        answer = browser.post("/jobs", files={"file": ("take.c3d", upload)}, data={"window": "6", "formulation": "ilp"})
    assert answer.status_code == 303
    job = httpx.get(f"{client.base_url}/v1{answer.headers['location']}", headers={"Authorization": f"Bearer {ALICE}"}).json()
    assert job["source"] == "take.c3d" and job["windows_total"] == len(window_spans(12, 6))
    page = browser.get(answer.headers["location"])
    assert "ilp · window 6" in page.text and "39 markers · 12 frames" in page.text


def test_the_forms_parameters_alone_keep_the_documents_formulation(client):
    """Parameters with the formulation left at the document's ran lp-l1 on a document asking for ilp."""
    document = document_json(generated_capture(frames=8, seed=1), LabelingOptions(formulation="ilp", window=4))
    browser = _signed_in(client)
    answer = browser.post("/jobs", files={"file": ("take.json", document)}, data={"parameters": '{"time_limit": 5}'})
    assert answer.status_code == 303
    page = browser.get(answer.headers["location"]).text
    options = page.split("<dt>Options</dt>")[1].split("</dd>")[0]
    assert "ilp (time_limit 5)" in options and "lp-l1" not in options


def test_the_forms_options_for_a_document_are_read_as_for_an_upload(client):
    """For a capture document "maybe" was stored as second_pass false, and a "name" among the
    parameters ran mht in place of the ilp chosen; an upload refused the one and kept ilp."""
    document = document_json(generated_capture(frames=8, seed=1), LabelingOptions(window=4))
    browser = _signed_in(client)
    answer = browser.post("/jobs", files={"file": ("take.json", document)}, data={"second_pass": "maybe"})
    assert answer.status_code == 422 and "second_pass: expected true or false" in answer.text, answer.text[-3000:]
    answer = browser.post("/jobs", files={"file": ("take.json", document)},
                          data={"formulation": "ilp", "parameters": '{"name": "mht", "time_limit": 5}'})
    assert answer.status_code == 303
    options = browser.get(answer.headers["location"]).text.split("<dt>Options</dt>")[1].split("</dd>")[0]
    assert "ilp" in options and "mht" not in options


def test_a_done_jobs_page_counts_doubt_on_the_labels_it_draws(client):
    """The page summed the windows' counts, from before the second pass: 28.5 % beside a
    warning line of 32.7 % on the basket sprint."""
    capture = generated_capture(frames=150, seed=0, ghosts_per_frame=8.0, noise_mm=2.5)
    options = LabelingOptions(window=10)
    labeled = CaptureLabeling(capture, options).label()[0]
    expected = doubtful_fraction(labeled.confidence, labeled.occluded)
    browser = _signed_in(client)
    answer = browser.post("/jobs", files={"file": ("take.json", document_json(capture, options))})
    job_id = answer.headers["location"].rsplit("/", 1)[1]
    api = httpx.Client(base_url=client.base_url, headers={"Authorization": f"Bearer {ALICE}"}, timeout=60)
    assert wait_for(api, f"{job_id}")["state"] == "done"
    page = browser.get(answer.headers["location"]).text
    assert f"{100 * expected:.1f} % of labels doubtful" in page
    ticked = labeled.names[:10]  # more than are drawn: the last two were left out without a word
    page = browser.get(answer.headers["location"], params={"markers": ticked}).text
    assert f"not drawn: {', '.join(ticked[8:])} (up to 8 at once)" in page


def test_the_list_pages_through_older_jobs(tmp_path, monkeypatch):
    """The list stopped at its newest 100 jobs, with no way to the older ones."""
    from service.web import listing

    monkeypatch.setattr(listing, "LISTED_JOBS", 2)
    document = document_json(generated_capture(frames=6, seed=1), LabelingOptions(window=3))
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}")) as local:
        ids = [local.post("/v1/jobs", content=document, headers={"content-type": "application/json"}).json()["id"]
               for _ in range(5)]
        newest, oldest = local.get("/").text, local.get("/?older=4").text
        assert local.get("/?older=-1").status_code == 422
    assert newest.count("<tr data-job=") == 2 and ids[-1] in newest and 'href="/?older=2"' in newest
    assert "Jobs 1-2 of 5" in newest and "Newer jobs" not in newest
    assert oldest.count("<tr data-job=") == 1 and ids[0] in oldest and 'href="/?older=2"' in oldest
    assert "Older jobs" not in oldest


def test_a_finished_job_is_removed_with_all_it_stored(tmp_path):
    """The store only grew: DELETE answered 409 for a finished job and nothing else removed one."""
    import sqlite3

    db = tmp_path / "jobs.db"
    document = document_json(generated_capture(frames=6, seed=1), LabelingOptions(window=3))
    with serving(Settings(db=f"sqlite:///{db}")) as local:
        kept, gone, by_page = (local.post("/v1/jobs", content=document, headers={"content-type": "application/json"})
                               .json()["id"] for _ in range(3))
        for job_id in (kept, gone, by_page):
            assert wait_for(local, job_id)["state"] == "done"
        assert local.delete(f"/v1/jobs/{gone}", params={"remove": "true"}).status_code == 204
        assert local.get(f"/v1/jobs/{gone}").status_code == 404
        assert local.delete(f"/v1/jobs/{gone}", params={"remove": "true"}).status_code == 404
        assert "Delete job" in local.get(f"/jobs/{by_page}").text
        answer = local.post(f"/jobs/{by_page}/delete", headers={"Origin": str(local.base_url).rstrip("/")})
        assert answer.status_code == 303 and answer.headers["location"] == "/"
        assert local.get(f"/v1/jobs/{kept}").json()["state"] == "done"
    with sqlite3.connect(db) as store:
        for table in ("jobs", "windows"):
            ids = {row[0] for row in store.execute(f"SELECT {'id' if table == 'jobs' else 'job_id'} FROM {table}")}
            assert ids == {kept}, table


def _uploaded_take(local: httpx.Client, folder: Path, frames: int, name: str, **fields: str) -> str:
    """A generated take of ``frames`` frames uploaded as a C3D named ``name``, labeled: its job id."""
    truth = generate_scene(n_frames=frames, seed=2)
    write_labeled(folder / "take.c3d", LabeledTrajectories(truth.names, truth.positions,
                                                           np.zeros(truth.positions.shape[:2], dtype=bool), truth.rate))
    job_id = local.post("/v1/jobs", files={"file": (name, (folder / "take.c3d").read_bytes())},
                        data={"window": "6", **fields}).json()["id"]
    assert wait_for(local, job_id)["state"] == "done"
    return str(job_id)


def test_a_span_jobs_page_counts_frames_as_the_take_does(tmp_path):
    """Warnings name take frames (2181-2640) while the plots counted from the span's start."""
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}")) as local:
        job_id = _uploaded_take(local, tmp_path, 40, "take.c3d", start="12", end="30")
        page = local.get(f"/jobs/{job_id}").text
        timeline = local.get(f"/jobs/{job_id}/plots/timeline.svg")
    assert "18 frames (frames 12–29 of the take" in page
    assert timeline.status_code == 200 and b"frame of the take" in timeline.content


def test_a_download_is_named_after_the_take(tmp_path):
    """Every download was markerflow-<id>.<format>, whatever the take."""
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}")) as local:
        job_id = _uploaded_take(local, tmp_path, 12, "gång 1.c3d")
        disposition = local.get(f"/jobs/{job_id}/result.csv").headers["content-disposition"]
    assert disposition == (f'attachment; filename="g_ng_1_labeled-{job_id[:8]}.csv"; '
                           f"filename*=UTF-8''g%C3%A5ng%201_labeled-{job_id[:8]}.csv")


def test_an_upload_chooses_one_pass(tmp_path):
    """A capture document could turn the second pass off; an upload could not (an unknown field)."""
    import json

    from service.server.store import store_for

    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    with serving(Settings(db=db)) as local:
        job_id = _uploaded_take(local, tmp_path, 12, "take.c3d", second_pass="false")
        refused = local.post("/v1/jobs", files={"file": ("take.c3d", (tmp_path / "take.c3d").read_bytes())},
                             data={"second_pass": "no"})
    assert json.loads(store_for(db).input(job_id))["second_pass"] is False
    assert refused.status_code == 422 and "second_pass: expected true or false" in refused.text


def test_a_jobs_page_offset_past_the_database_integers_is_a_422(client):
    """?older= past 2**63 reached SQLite and answered 500 (OverflowError)."""
    browser = _signed_in(client)
    assert browser.get("/?older=9223372036854775808").status_code == 422
    assert browser.get("/?older=5").status_code == 200
