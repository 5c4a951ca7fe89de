"""``markerflow integrality`` on a corpus it cannot use, or with a formulation that refuses a
window, is one line naming the file (they were a JSONDecodeError, a KeyError and a
FormulationError as tracebacks, the last after minutes without progress)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from service.cli.app import app

CORPUS = Path(__file__).resolve().parent / "fixtures" / "integrality"


def _corpus(tmp_path: Path, record: str) -> Path:
    folder = tmp_path / "corpus"
    shutil.copytree(CORPUS / "random-3x4", folder / "random-3x4")
    (folder / "recorded.json").write_text(record)
    return folder


def _first_window() -> dict:
    return json.loads((CORPUS / "recorded.json").read_text())["random-3x4"][0]


@pytest.mark.parametrize(("record", "said"), [
    ("{\n oops", "recorded.json: not JSON"),
    (json.dumps({"random-3x4": [{"file": "random-3x4/000.npz"}]}), "random-3x4[0] needs 'file' and 'ilp_optimum'"),
])
def test_a_broken_corpus_is_one_line(tmp_path: Path, record: str, said: str) -> None:
    result = CliRunner().invoke(app, ["integrality", "--corpus", str(_corpus(tmp_path, record))])
    assert result.exit_code == 2 and said in result.output and "Traceback" not in result.output


def test_a_window_a_formulation_refuses_is_named(tmp_path: Path) -> None:
    folder = _corpus(tmp_path, json.dumps({"random-3x4": [_first_window()]}))
    spec = tmp_path / "tiny.toml"
    spec.write_text('[formulation]\nname = "dp-extended"\nmax_states = 1\n')
    result = CliRunner().invoke(app, ["-q", "integrality", "--corpus", str(folder), "-f", str(spec)])
    assert result.exit_code == 2 and "random-3x4/000.npz: dp-extended: joint state space" in result.output


def test_a_sound_corpus_is_scored(tmp_path: Path) -> None:
    folder = _corpus(tmp_path, json.dumps({"random-3x4": [_first_window()]}))
    result = CliRunner().invoke(app, ["-q", "integrality", "--corpus", str(folder)])
    assert result.exit_code == 0 and "random-3x4" in result.output
