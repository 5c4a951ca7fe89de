"""``markerflow boxes`` and ``mot-eval`` end to end on TUD-Campus (71 frames), and their one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import motmetrics
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
