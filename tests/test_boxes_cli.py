"""``markerflow boxes`` and ``mot-eval`` end to end on TUD-Campus (71 frames), and their one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import motmetrics
import numpy as np
import pytest
from typer.testing import CliRunner

from service.cli.app import app

DETECTIONS = Path(__file__).resolve().parents[2] / "shared" / "data" / "mot15_sort_frcnn_detections" / "TUD-Campus" / "det.txt"
GT = Path(motmetrics.__file__).parent / "data" / "TUD-Campus" / "gt.txt"

runner = CliRunner()


def _hota(tmp_path: Path, formulation: str) -> float:
    result = tmp_path / f"{formulation}.txt"
    run = runner.invoke(app, ["boxes", str(DETECTIONS), "--out", str(result), "--formulation", formulation, "--json"])
    assert run.exit_code == 0, run.output
    assert json.loads(run.stdout)["frames"] == 71
    scored = runner.invoke(app, ["mot-eval", str(result), str(GT), "--json"])
    assert scored.exit_code == 0, scored.output
    return float(json.loads(scored.stdout)["hota"])


@pytest.mark.skipif(not DETECTIONS.exists(), reason="needs ../shared/data (TUD-Campus detections)")
def test_boxes_then_mot_eval_on_tud_campus(tmp_path):
    lp, baseline = _hota(tmp_path, "lp-l1"), _hota(tmp_path, "nn-hungarian")
    assert 0 < lp <= 1 and 0 < baseline <= 1
    assert lp >= baseline - 0.03


def test_errors_are_one_line(tmp_path):
    bad = tmp_path / "det.txt"
    bad.write_text("1,-1,10,10,5,5,0.9\n2,-1,10,10\n")
    for args in (["boxes", str(bad), "--out", str(tmp_path / "r.txt")],
                 ["boxes", str(tmp_path / "missing.txt"), "--out", str(tmp_path / "r.txt")],
                 ["mot-eval", str(tmp_path / "missing.txt"), str(bad)]):
        run = runner.invoke(app, args)
        assert run.exit_code == 2, run.output
        assert len(run.output.strip().splitlines()) == 1 and run.output.startswith("error:")


def test_the_newcomer_test_is_on_by_default_and_can_be_turned_off(tmp_path):
    # A walks right in frames 1..10 and is gone; from frame 14 B walks left inside A's widening
    # forecast; two people stand far off, so that the boxes span a camera's sizes
    # (``tests/test_boxes_births.py``). The newcomer test makes B a new person; the window's
    # costs alone hand B to A.
    rng = np.random.default_rng(0)
    rows = [(f, 100.0 + 3 * f, 100.0, 40.0, 100.0) for f in range(1, 11)]
    rows += [(f, 242.0 - 3 * f, 110.0, 44.0, 110.0) for f in range(14, 41)]
    rows += [(f, x, y, w, h) for f in range(1, 41) for x, y, w, h in ((1500.0, 100.0, 20.0, 50.0), (1600.0, 500.0, 120.0, 300.0))]
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{x - w / 2 + rng.normal(0, 1):.2f},{y - h / 2 + rng.normal(0, 1):.2f},{w},{h},1\n"
                           for f, x, y, w, h in sorted(rows)))
    info = tmp_path / "seqinfo.ini"
    info.write_text("[Sequence]\nname=walkers\nseqLength=40\nimWidth=1920\nimHeight=1080\n")
    tracks = {}
    for flag in ([], ["--no-newcomer-test"]):
        run = runner.invoke(app, ["boxes", str(det), "--out", str(tmp_path / "r.txt"), "--seqinfo", str(info), "--json", *flag])
        assert run.exit_code == 0, run.output
        summary = json.loads(run.stdout)
        assert summary["newcomer_test"] == (not flag)
        tracks[bool(flag)] = summary["tracks"]
    assert tracks == {False: 4, True: 3}  # A, B and the two standing; B handed to A without the test


@pytest.mark.skipif(not DETECTIONS.exists(), reason="needs ../shared/data (TUD-Campus detections)")
def test_occluded_boxes_are_written_unless_turned_off(tmp_path):
    counts = {}
    for flag in ([], ["--no-occluded"]):
        result = tmp_path / f"r{len(flag)}.txt"
        run = runner.invoke(app, ["boxes", str(DETECTIONS), "--out", str(result), "--json", *flag])
        assert run.exit_code == 0, run.output
        summary = json.loads(run.stdout)
        rows = np.loadtxt(result, delimiter=",", ndmin=2)
        assert len(rows) == summary["tracked_boxes"] + summary["occluded_boxes"]
        assert (rows[:, 6] == 0).sum() == summary["occluded_boxes"]
        counts[bool(flag)] = summary["occluded_boxes"]
    assert counts[True] == 0 < counts[False]


@pytest.mark.skipif(not DETECTIONS.exists(), reason="needs ../shared/data (TUD-Campus detections)")
def test_frames_numbered_in_steps_track_nothing_and_say_so_and_the_empty_result_scores_zero(tmp_path):
    rows = np.loadtxt(DETECTIONS, delimiter=",")
    rows[:, 0] *= 50  # one detection frame in 50: no box has a successor to start a track with
    stepped, result = tmp_path / "det.txt", tmp_path / "result.txt"
    np.savetxt(stepped, rows, fmt="%g", delimiter=",")
    run = runner.invoke(app, ["boxes", str(stepped), "--out", str(result), "--json"])
    assert run.exit_code == 0, run.output
    assert json.loads(run.stdout)["tracked_boxes"] == 0 and result.read_text() == ""
    assert "none of the 321 detections is in a track" in run.stderr
    scored = runner.invoke(app, ["mot-eval", str(result), str(GT), "--json"])
    assert scored.exit_code == 0, scored.output
    scores = json.loads(scored.stdout)
    assert scores["hota"] == scores["mota"] == scores["idf1"] == 0 and scores["gt_ids"] > 0


@pytest.mark.skipif(not DETECTIONS.exists(), reason="needs ../shared/data (TUD-Campus detections)")
def test_a_result_given_as_ground_truth_is_refused(tmp_path):
    result = tmp_path / "result.txt"
    assert runner.invoke(app, ["boxes", str(DETECTIONS), "--out", str(result)]).exit_code == 0
    swapped = runner.invoke(app, ["mot-eval", str(GT), str(result)])
    assert swapped.exit_code == 2 and "is it a result file" in swapped.output


@pytest.mark.skipif(not DETECTIONS.exists(), reason="needs ../shared/data (TUD-Campus detections)")
def test_a_detection_given_twice_is_tracked_once(tmp_path):
    """Each duplicated box used to start a second object of its own (25 tracks instead of 11)."""
    doubled = tmp_path / "det.txt"
    doubled.write_text("".join(line + "\n" + line + "\n" for line in DETECTIONS.read_text().splitlines()))
    for det, out in ((DETECTIONS, "once.txt"), (doubled, "twice.txt")):
        assert runner.invoke(app, ["boxes", str(det), "--out", str(tmp_path / out)]).exit_code == 0
    assert (tmp_path / "twice.txt").read_text() == (tmp_path / "once.txt").read_text()
