"""A second labeling from the spreads the first measured, kept when its rigid pairs agree better
with the labeled first frame."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from service_fixtures import document_json, generated_capture

import service.labeling.second_pass as second_pass_module
from formulations.confidence.two_readings import agreed_confidence
from service.capture.capture import LabelingOptions
from service.io.formats import read_labeled
from service.io.formats.csv import read_csv_labeled
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.outcome import WindowOutcome
from service.labeling.second_pass import second_pass
from service.labeling.stats import REPORTED_DOUBTFUL_BELOW
from service.server.results import trajectories_from_bytes
from service.server.runner import run_job
from service.server.store import store_for

TENNIS = DATA / "c3d_kineticstoolkit" / "kinematics_tennis_serve.c3d"  # 50 Hz, the arm ~100 mm per frame
FRAMES = 400  # frames 0-399 hold the elbow glitch at 190 and the exchange after it


def _correct(truth: Path, output: Path, frames: int | None = None) -> float:
    """Share of the file's own samples (in its first ``frames``) that the output labels with their own point."""
    given, written = read_labeled(truth), read_labeled(output)
    own = written.positions[:frames, [written.names.index(n) for n in given.names]]
    present = np.isfinite(given.positions[:frames]).all(axis=2)
    same = np.linalg.norm(np.nan_to_num(own - given.positions[:frames], nan=1e9), axis=2) < 1e-3
    return float((same & present).sum() / present.sum())


def _wrong_and_sure(truth: Path, output: Path, frames: int) -> float:
    """Share of a CSV output's labels (in its first ``frames``) on another point than the file's
    own, with no doubt reported: the errors a user would not look at."""
    given, written = read_labeled(truth), read_csv_labeled(output)
    order = [written.names.index(n) for n in given.names]
    own = written.positions[:frames, order]
    labeled = np.isfinite(own).all(axis=2)
    same = np.linalg.norm(np.nan_to_num(own - given.positions[:frames], nan=1e9), axis=2) < 1e-3
    sure = written.confidence[:frames, order] >= REPORTED_DOUBTFUL_BELOW
    return float((labeled & ~same & sure).sum() / labeled.sum())


def _track(output: Path, *flags: str) -> dict:
    run = subprocess.run(
        [sys.executable, "-m", "service.cli", "track", str(TENNIS), "--out", str(output), "--json", *flags],
        capture_output=True, text=True, check=True,
    )
    summary: dict = json.loads(run.stdout)
    return summary


def test_the_tennis_serve_is_right_only_with_the_second_pass(tmp_path: Path) -> None:
    """One pass learns the arm's spreads too late: the arm's markers exchange after the file's
    own elbow glitch at frame 190. The second pass starts from the spreads of the whole take.
    Its first 400 frames hold the case (95.70 against 99.87 % on 2026-12-03; the whole take,
    97.05 against 99.92 %, took three times as long)."""
    once = _track(tmp_path / "once.csv", "--one-pass", "--end", str(FRAMES))
    twice = _track(tmp_path / "twice.csv", "--end", str(FRAMES))
    assert once["second_pass"] is None
    assert _correct(TENNIS, tmp_path / "once.csv", FRAMES) < 0.98
    assert _correct(TENNIS, tmp_path / "twice.csv", FRAMES) > 0.99
    choice = twice["second_pass"]
    assert choice["kept"] == 2 and choice["second_off_mm"] < choice["first_off_mm"]
    # The errors one pass is sure of are gone, not merely doubted (2.5 % of its labels against
    # 0.06 % on 2026-12-04). The two passes' disagreement is doubted (two_readings): the more one
    # pass gets wrong, the more right labels the second doubts (3.2 -> 5.3 % doubtful since
    # distances are learned from sightings only), so the doubt's share is not what is compared.
    assert _wrong_and_sure(TENNIS, tmp_path / "once.csv", FRAMES) > 0.01
    assert _wrong_and_sure(TENNIS, tmp_path / "twice.csv", FRAMES) < 0.002
    line = subprocess.run(
        [sys.executable, "-m", "service.cli", "-q", "track", str(TENNIS), "--out", str(tmp_path / "line.c3d"),
         "--end", str(FRAMES)],
        capture_output=True, text=True, check=True, env={**os.environ, "COLUMNS": "400"},
    ).stdout
    assert (f"second pass kept (rigid pairs {choice['first_off_mm']:.1f} -> {choice['second_off_mm']:.1f} mm off the "
            f"first frame; {choice['first_doubtful']:.1%} -> {choice['second_doubtful']:.1%} doubtful)") in line


def _stats_doubt(outcomes: list[WindowOutcome], doubtful: int) -> list[WindowOutcome]:
    return [replace(o, stats=replace(o.stats, labels=100, doubtful=doubtful)) for o in outcomes]


@pytest.mark.parametrize(
    ("first", "off", "kept"),
    [(10, (5.0, 3.0), 2), (10, (5.0, 5.0), 1), (10, (3.0, 5.0), 1), (10, (np.nan, np.nan), 1), (70, (4.0, 2.0), 2),
     (2, (5.0, 3.0), 1), (0, (5.0, 3.0), 1), (80, (5.0, 3.0), 1)],
)
def test_the_pass_kept_is_the_one_closer_to_the_first_frame(monkeypatch, first, off, kept) -> None:
    """The first pass's doubt says whether a second runs (above 2 %, up to 75 %); the rigid
    pairs' disagreement with the first frame says which is kept, whatever the doubt says."""
    capture = generated_capture(frames=40, seed=3)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10))
    outcomes = _stats_doubt(list(labeling.windows()), first)
    ran, judged = [], []
    real = second_pass_module.label_windows

    def counted(*args, **kwargs):
        ran.append(_stats_doubt(list(real(*args, **kwargs)), 90))  # far more doubtful, kept or not
        return ran[-1]

    def disagreement(capped, judged_triples):
        judged.append(len(capped))
        return np.array(off)

    monkeypatch.setattr(second_pass_module, "label_windows", counted)
    monkeypatch.setattr(second_pass_module, "disagreement", disagreement)
    monkeypatch.setattr(second_pass_module, "labels_taken", lambda points, *_, **__: np.zeros(points[0].shape, bool))
    chain, formulation = labeling._association, labeling.formulation  # noqa: SLF001  (the pass as refine runs it)
    kept_outcomes, choice = second_pass(chain, formulation, labeling._first, 40, 10, outcomes, labeling.result)  # noqa: SLF001
    assert choice.kept == kept
    assert bool(ran) == bool(judged) == (2 < first <= 75)
    if not ran:
        assert kept_outcomes is outcomes
        assert (choice.first_doubtful, choice.second_doubtful, choice.first_off_mm) == (first / 100, None, None)
    else:  # the kept pass's labels, each confidence judged with the other pass's label
        source, other = (ran[0], outcomes) if kept == 2 else (outcomes, ran[0])
        for mine, own, theirs in zip(kept_outcomes, source, other, strict=True):
            assert np.array_equal(mine.point_index, own.point_index)
            agreed = agreed_confidence(own.confidence, own.point_index, theirs.confidence, theirs.point_index)
            assert np.allclose(mine.confidence, agreed)
            assert mine.stats.doubtful == int((~(mine.point_index < 0) & (agreed < 0.9)).sum())
        expected = [None if np.isnan(v) else v for v in off]
        assert (choice.first_off_mm, choice.second_off_mm, choice.second_doubtful) == (*expected, 0.9)


@pytest.mark.parametrize("kept", [1, 2])
def test_markers_the_other_pass_labels_better_come_from_it(monkeypatch, kept: int) -> None:
    """The kept pass's windows, but the markers ``pass_merge`` gives the other pass carry the
    other pass's labels, fills, confidences and state rows; the summary counts them."""
    capture = generated_capture(frames=40, seed=3)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10))
    outcomes = _stats_doubt(list(labeling.windows()), 10)
    ran = []
    real = second_pass_module.label_windows

    def shifted(*args, **kwargs):  # a second pass that differs visibly in every column
        ran.append([replace(o, point_index=o.point_index + 1000, state=replace(o.state, position=o.state.position + 1.0))
                    for o in real(*args, **kwargs)])
        return ran[-1]

    monkeypatch.setattr(second_pass_module, "label_windows", shifted)
    off = [5.0, 3.0] if kept == 2 else [3.0, 5.0]
    monkeypatch.setattr(second_pass_module, "disagreement", lambda *_: np.array(off))
    first_two = lambda points, *_, **__: np.broadcast_to(np.arange(points[0].shape[1]) < 2, points[0].shape)  # noqa: E731
    monkeypatch.setattr(second_pass_module, "labels_taken", first_two)
    first_labels = labeling.result(outcomes)  # what the judges read is stubbed above
    chain, formulation = labeling._association, labeling.formulation  # noqa: SLF001
    merged, choice = second_pass(chain, formulation, labeling._first, 40, 10, outcomes, lambda _: first_labels)  # noqa: SLF001
    own, other = (ran[0], outcomes) if kept == 2 else (outcomes, ran[0])
    assert choice.kept == kept and choice.taken_from_other == 2
    for window, mine, theirs in zip(merged, own, other, strict=True):
        assert np.array_equal(window.point_index[:, :2], theirs.point_index[:, :2])
        assert np.array_equal(window.point_index[:, 2:], mine.point_index[:, 2:])
        assert np.array_equal(window.state.position[:2], theirs.state.position[:2])
        assert np.array_equal(window.state.position[2:], mine.state.position[2:])
        assert window.stats.template == mine.stats.template


def test_a_stop_abandons_the_second_pass(monkeypatch) -> None:
    labeling = CaptureLabeling(generated_capture(frames=40, seed=3), LabelingOptions(window=10))
    outcomes = _stats_doubt(list(labeling.windows()), 5)
    assert labeling.refine(outcomes, stop=lambda: True) is None
    assert labeling.choice is None


def test_a_job_stores_the_kept_pass_windows_with_its_result(monkeypatch, tmp_path: Path) -> None:
    """A second pass the labeler keeps replaces the job's stored windows: what resuming or a
    partial result reads is the labeling the result was assembled from."""
    # a second pass runs and is kept, in the job and in the library alike
    monkeypatch.setattr(second_pass_module, "doubtful_share", lambda outcomes: 0.5)
    monkeypatch.setattr(second_pass_module, "disagreement", lambda *args: np.array([5.0, 1.0]))
    real = second_pass_module.label_windows

    def marked(*args, **kwargs):
        return [replace(o, stats=replace(o.stats, status="second pass")) for o in real(*args, **kwargs)]

    monkeypatch.setattr(second_pass_module, "label_windows", marked)
    capture, options = generated_capture(frames=60, seed=5), LabelingOptions(window=10)
    db = f"sqlite:///{tmp_path / 'jobs.db'}"
    store = store_for(db)
    labeling = CaptureLabeling(capture, options)
    job, _ = store.add("local", "json", document_json(capture, options).encode(), labeling.n_windows)
    assert run_job(db, job.id) == "done"
    expected, windows = labeling.label()
    assert labeling.choice is not None and labeling.choice.kept == 2
    result = trajectories_from_bytes(store.result(job.id))
    assert np.array_equal(result.positions, expected.positions, equal_nan=True)
    assert [w.stats["status"] for w in store.windows(job.id)] == ["second pass"] * labeling.n_windows
    assert [w.status for w in windows] == ["second pass"] * labeling.n_windows
    assert store.known(job.id).windows_done == labeling.n_windows


@pytest.mark.parametrize(("flag", "expected"), [(None, False), (True, True), (False, False)])
def test_track_keeps_a_documents_second_pass_unless_a_flag_is_given(monkeypatch, tmp_path: Path, flag, expected) -> None:
    """``track`` overrides a capture document's ``second_pass`` only with --second-pass/--one-pass."""
    import service.cli.track as track_module

    document = tmp_path / "capture.json"
    document.write_text(document_json(generated_capture(frames=20, seed=1), LabelingOptions(second_pass=False)))
    given: list[LabelingOptions] = []

    class Recorded(CaptureLabeling):
        def __init__(self, capture, options):
            given.append(options)
            super().__init__(capture, options)

    monkeypatch.setattr(track_module, "CaptureLabeling", Recorded)
    track_module.run_track(document, tmp_path / "out.csv", None, None, False, as_json=True, second_pass=flag)
    assert [options.second_pass for options in given] == [expected]
