"""The web page in a real headless Chromium (Debian's, driven by Playwright; nothing is
downloaded) against the real server on a loopback port: sign in, upload a generated take
through the form, watch it reach done, see the plots drawn, download the C3D and find the
library's labels in it; another token sees none of it; /docs and /redoc render offline.
Skipped, saying why, where Chromium cannot start."""

from __future__ import annotations

import re
import shutil
from urllib.parse import urlparse

import numpy as np
import pytest
from service_fixtures import document_json, generated_capture, serving
from test_subject_model import chain

from formulations.subject.fit import fit_subject
from service.capture.capture import LabelingOptions
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, is_unlabeled
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.spans import window_spans
from service.server.settings import Settings

playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (the test extra)")

ALICE, BOB = "alice-token-0123456789", "bob-token-0123456789ab"
OPTIONS = LabelingOptions(window=20)
TIMEOUT_MS = 60_000
REDOC_CREDIT = "https://cdn.redoc.ly/redoc/logo-mini.svg"


@pytest.fixture(scope="module")
def browser():
    executable = shutil.which("chromium") or shutil.which("chromium-browser")
    if executable is None:
        pytest.skip("no chromium on PATH (Debian's chromium package; .ci/run installs it)")
    with playwright_api.sync_playwright() as playwright:
        try:
            chromium = playwright.chromium.launch(executable_path=executable, headless=True)
        except playwright_api.Error as error:
            pytest.skip(f"Chromium cannot start: {str(error).splitlines()[0]}")
        yield chromium
        chromium.close()


@pytest.fixture(scope="module")
def base_url(tmp_path_factory):
    db = tmp_path_factory.mktemp("web") / "jobs.db"
    settings = Settings(db=f"sqlite:///{db}", tokens={"alice": ALICE, "bob": BOB}, events_poll_seconds=0.05)
    with serving(settings) as client:
        yield str(client.base_url).rstrip("/")


@pytest.fixture(scope="module")
def capture():
    return generated_capture(frames=100, seed=4)


def _signed_in(browser, base_url: str, token: str):
    context = browser.new_context(accept_downloads=True)
    page = context.new_page()
    page.set_default_timeout(TIMEOUT_MS)
    assert page.goto(base_url + "/").status == 401
    page.get_by_label("Token").fill(token)
    page.get_by_role("button", name="Sign in").click()
    page.get_by_role("heading", name="Jobs", exact=True).wait_for()
    return context, page


@pytest.fixture(scope="module")
def done_job(browser, base_url, capture, tmp_path_factory):
    """Alice's job, uploaded through the form as a capture document; its page once done."""
    folder = tmp_path_factory.mktemp("upload")
    (folder / "take.json").write_text(document_json(capture))
    context, page = _signed_in(browser, base_url, ALICE)
    page.get_by_label("Capture file").set_input_files(folder / "take.json")
    page.get_by_label("Window (frames)").fill(str(OPTIONS.window))
    page.get_by_role("button", name="Submit").click()
    page.wait_for_url(re.compile(r"/jobs/[0-9a-f]{32}$"))
    # The page follows the event stream and reloads itself when the job ends.
    page.locator("#state:not([data-state=queued]):not([data-state=running])").wait_for()
    assert page.locator("#state").inner_text() == "done", page.locator("dl.facts").inner_text()
    yield page, page.url.rsplit("/", 1)[1]
    context.close()


def test_the_job_page_follows_the_job_to_done_and_draws_its_plots(done_job):
    page, _ = done_job
    assert page.title().startswith("Job take.json")
    windows = len(window_spans(100, OPTIONS.window))
    assert page.locator("#progress-text").inner_text() == f"{windows} of {windows} windows"
    for plot in ("certificate", "timeline", "trajectories"):
        image = page.locator(f"#{plot}-plot")
        image.scroll_into_view_if_needed()
        page.wait_for_function("img => img.complete", arg=image.element_handle())
        assert image.evaluate("img => img.naturalWidth") > 100, plot
        svg = page.request.get(image.evaluate("img => img.src")).text()
        drawn = re.findall(r'<path[^>]* d="M[^"]+"', svg)
        assert len(drawn) > 20, plot  # axes, ticks and the data: far more than an empty frame
    rows = page.locator("#marker-states tbody tr")
    assert rows.count() == 39


def test_the_downloaded_c3d_is_the_librarys(done_job, capture, tmp_path):
    page, _ = done_job
    with page.expect_download() as download:
        page.get_by_role("link", name="C3D").click()
    download.value.save_as(tmp_path / "served.c3d")
    expected, _ = CaptureLabeling(capture, OPTIONS).label()
    write_labeled(tmp_path / "library.c3d", expected)
    served, library = read_labeled(tmp_path / "served.c3d"), read_labeled(tmp_path / "library.c3d")
    assert served.names == library.names
    assert np.array_equal(served.positions, library.positions, equal_nan=True)
    # the markers, then the points no marker took as unlabeled trajectories *N
    assert [name for name in served.names if not is_unlabeled(name)] == expected.names
    assert len(served.names) == len(expected.names) + expected.unlabeled.shape[1]


def test_the_pages_fit_a_400_px_window(done_job):
    """At 400 px the form was cut off and the jobs table (891 px) scrolled the whole page."""
    page, job_id = done_job
    base = page.url.split("/jobs/")[0]
    page.set_viewport_size({"width": 400, "height": 800})
    try:
        for path in ("/", f"/jobs/{job_id}"):
            page.goto(base + path)
            page.locator("details").evaluate_all("all => all.forEach(d => d.open = true)")
            assert page.evaluate("document.documentElement.scrollWidth") <= 400, path
            for field in page.locator("form#upload input, form#upload select").all():
                box = field.bounding_box()
                assert box is None or box["x"] + box["width"] <= 400, path
    finally:
        page.set_viewport_size({"width": 1280, "height": 800})


def _slow_job(page, base_url: str) -> str:
    """Bob's job that runs for a while (the ILP without its LP shortcut on 200-frame windows)."""
    slow = LabelingOptions(formulation={"name": "ilp", "lp_first": False}, window=200)
    body = document_json(generated_capture(frames=402, seed=3, ghosts_per_frame=15.0), slow)
    answer = page.request.post(f"{base_url}/v1/jobs", data=body,
                               headers={"Authorization": f"Bearer {BOB}", "Content-Type": "application/json"})
    return str(answer.json()["id"])


def test_a_running_job_page_says_when_its_stream_is_lost(browser, base_url):
    """With the server down the page kept saying "running" with no sign the stream was gone."""
    context, page = _signed_in(browser, base_url, BOB)
    try:
        job_id = _slow_job(page, base_url)
        page.route("**/events", lambda route: route.abort())  # the server gone: the stream cannot connect
        page.goto(f"{base_url}/jobs/{job_id}")
        page.wait_for_function("document.getElementById('progress-text').textContent.includes('connection')")
        assert "connection to the server lost; retrying" in page.locator("#progress-text").inner_text()
        page.request.delete(f"{base_url}/v1/jobs/{job_id}", headers={"Authorization": f"Bearer {BOB}"})
    finally:
        context.close()


def test_a_job_page_whose_stream_is_refused_says_so_and_reloads(browser, base_url):
    """Refused with 429 (the token's streams all open elsewhere), the stream was closed for good
    and the page said "running" while the job finished."""
    context, page = _signed_in(browser, base_url, BOB)
    try:
        job_id = _slow_job(page, base_url)
        page.route("**/events", lambda route: route.fulfill(status=429, body='{"message": "20 event streams are open"}'))
        page.goto(f"{base_url}/jobs/{job_id}")
        page.wait_for_function("document.getElementById('progress-text').textContent.includes('refused')")
        assert "live progress refused by the server; reloading every 10 s" in page.locator("#progress-text").inner_text()
        page.wait_for_event("load", timeout=20_000)  # the page reloads by itself
        page.request.delete(f"{base_url}/v1/jobs/{job_id}", headers={"Authorization": f"Bearer {BOB}"})
    finally:
        context.close()


def test_another_token_sees_none_of_the_job(browser, base_url, done_job):
    _, job_id = done_job
    context, page = _signed_in(browser, base_url, BOB)
    try:
        assert job_id not in page.content()
        answer = page.goto(f"{base_url}/jobs/{job_id}")
        assert answer.status == 404 and page.get_by_role("heading", name="Not found").is_visible()
        for path in ("plots/timeline.svg", "result.c3d", "events"):
            assert page.request.get(f"{base_url}/jobs/{job_id}/{path}").status == 404, path
    finally:
        context.close()


def test_a_refused_upload_shows_the_apis_message_and_keeps_the_options(browser, base_url, tmp_path, capture):
    context, page = _signed_in(browser, base_url, BOB)
    try:
        (tmp_path / "take.json").write_text(document_json(capture))
        page.get_by_label("Capture file").set_input_files(tmp_path / "take.json")
        page.get_by_label("Formulation", exact=True).select_option("ilp")
        page.get_by_label("Formulation parameters (JSON, optional)").fill('{"time_limit": 10}')
        page.get_by_label("Window (frames)").fill("1")
        page.get_by_label("Window (frames)").evaluate("input => input.removeAttribute('min')")
        page.get_by_role("button", name="Submit").click()
        assert page.get_by_role("alert").inner_text().startswith("⚠ window:") or \
            page.locator("#upload-error").inner_text().startswith("window:")
        # the form was emptied: the user had to choose everything again
        assert page.get_by_label("Formulation", exact=True).input_value() == "ilp"
        assert page.get_by_label("Formulation parameters (JSON, optional)").input_value() == '{"time_limit": 10}'
        assert page.get_by_label("Window (frames)").input_value() == "1"
    finally:
        context.close()


def test_blank_options_keep_the_documents_own(browser, base_url, tmp_path, capture):
    """The form sent lp-l1 and window 20 over a document that asked for ilp and 30."""
    context, page = _signed_in(browser, base_url, BOB)
    try:
        (tmp_path / "own.json").write_text(document_json(capture, LabelingOptions(formulation="ilp", window=30)))
        page.get_by_label("Capture file").set_input_files(tmp_path / "own.json")
        page.get_by_role("button", name="Submit").click()
        page.wait_for_url(re.compile(r"/jobs/[0-9a-f]{32}$"))
        assert page.locator("dl.facts").inner_text().count("ilp · window 30") == 1
    finally:
        context.close()


def test_every_form_control_has_a_label(browser, base_url):
    context, page = _signed_in(browser, base_url, BOB)
    try:
        controls = page.locator("form#upload input, form#upload select")
        ids = [controls.nth(i).get_attribute("id") for i in range(controls.count())]
        assert ids and all(page.locator(f"label[for={name}]").count() == 1 for name in ids)
        page.keyboard.press("Tab")  # the first link takes the focus, visibly (keyboard use)
        assert page.evaluate("document.activeElement.tagName") == "A"
    finally:
        context.close()


@pytest.mark.parametrize(("path", "operations"), [("/docs", ".opblock"), ("/redoc", "[role=menuitem], li[data-item-id]")])
def test_api_docs_render_with_the_network_blocked(browser, base_url, path, operations):
    context = browser.new_context()
    outside = []

    def loopback_only(route):
        if urlparse(route.request.url).hostname == "127.0.0.1":
            return route.continue_()
        outside.append(route.request.url)
        return route.abort()

    context.route("**/*", loopback_only)
    try:
        page = context.new_page()
        page.set_default_timeout(TIMEOUT_MS)
        page.goto(base_url + path)
        page.locator(operations).first.wait_for()
        assert page.locator(operations).count() >= 8  # every operation of /v1 and the service routes
        assert page.get_by_text("/v1/jobs", exact=False).first.is_visible() or path == "/redoc"
        # ReDoc's sidebar credit is an image from its CDN; nothing else may leave the machine.
        assert set(outside) <= {REDOC_CREDIT}, outside
    finally:
        context.close()


def _chain_take(tmp_path) -> tuple[list[str], np.ndarray]:
    """A chain's names and its frames 120-159, after subject.json is fitted on frames 0-119."""
    names, positions, _ = chain(3, frames=160)
    (tmp_path / "subject.json").write_text(fit_subject(names, positions[:120]).model.to_json())
    return names, positions[120:].copy()


def _submit_with_model(page, tmp_path, names: list[str], held: np.ndarray) -> None:
    """Upload ``held`` as a .c3d with subject.json through the form, window 10; wait for the job's page."""
    write_labeled(tmp_path / "take.c3d", LabeledTrajectories(names, held, np.isnan(held).any(axis=2), 100.0))
    page.get_by_label("Capture file").set_input_files(tmp_path / "take.c3d")
    page.get_by_label("Subject model (JSON, optional)").set_input_files(tmp_path / "subject.json")
    page.get_by_label("Window (frames)").fill("10")
    page.get_by_role("button", name="Submit").click()
    page.wait_for_url(re.compile(r"/jobs/[0-9a-f]{32}$"))


def test_a_c3d_with_a_model_keeps_its_partly_labeled_frame_0(browser, base_url, tmp_path):
    """The form's model goes with a .c3d too: frame 0 lacks a marker, the model names it."""
    names, held = _chain_take(tmp_path)
    held[:5, 2] = np.nan
    context, page = _signed_in(browser, base_url, BOB)
    try:
        _submit_with_model(page, tmp_path, names, held)
        page.locator("#state:not([data-state=queued]):not([data-state=running])").wait_for()
        assert page.locator("#state").inner_text() == "done", page.locator("dl.facts").inner_text()
    finally:
        context.close()


def test_the_job_page_says_when_the_labels_do_not_fit_the_model(browser, base_url, tmp_path):
    """A .c3d whose frame 0 puts a marker 8 cm from where the model has it: the page warns, as the API does."""
    names, held = _chain_take(tmp_path)
    held[:, names.index("S1M2")] += [0.0, 80.0, 0.0]  # the lab placed it elsewhere this time
    context, page = _signed_in(browser, base_url, BOB)
    try:
        _submit_with_model(page, tmp_path, names, held)
        note = page.get_by_role("note").filter(has_text="do not fit")  # a done job adds what the labeling warns of
        assert note.inner_text().startswith("warning: the labels of frame 0 do not fit 1 of the model's segments")
    finally:
        context.close()
