"""``markerflow integrality`` on a corpus it cannot use, or with a formulation that refuses a
window, is one line naming the file (they were a JSONDecodeError, a KeyError and a
FormulationError as tracebacks, the last after minutes without progress)."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from typer.testing import CliRunner

from service.cli.app import app
from service.errors import InputError
from service.io.window_files import load_window

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


def _record(file: object, optimum: object) -> str:
    return json.dumps({"random-3x4": [{"file": file, "ilp_optimum": optimum}]})


@pytest.mark.parametrize(("record", "said"), [
    (json.dumps({"random-3x4": []}), "recorded.json: random-3x4 lists no window"),
    (json.dumps({}), "recorded.json: lists no corpus"),
    (_record("random-3x4/000.npz", "74.5"), "random-3x4[0] 'ilp_optimum' must be a finite number, not \"74.5\""),
    (_record("random-3x4/000.npz", None), "random-3x4[0] 'ilp_optimum' must be a finite number, not null"),
    (_record("random-3x4/000.npz", True), "'ilp_optimum' must be a finite number, not true"),
    (_record(3, 1.0), "random-3x4[0] 'file' must be a path in the corpus folder, not 3"),
])
def test_a_corpus_without_windows_or_numeric_optima_is_one_line(tmp_path: Path, record: str, said: str) -> None:
    """An empty list was a numpy ValueError traceback, a string or null optimum a TypeError one."""
    result = CliRunner().invoke(app, ["-q", "integrality", "--corpus", str(_corpus(tmp_path, record))])
    assert result.exit_code == 2 and said in result.output and "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1


@pytest.mark.parametrize(("damage", "said"), [
    (lambda data: b"", "window.npz: not a markerflow window file (No data left in file)"),
    (lambda data: data[:500], "window.npz: not a markerflow window file (File is not a zip file)"),
    (lambda data: data[:-30], "window.npz: not a markerflow window file"),
])
def test_an_empty_or_truncated_window_file_is_named(tmp_path: Path, damage: Callable[[bytes], bytes], said: str) -> None:
    """An empty .npz printed a bare "aborted" (exit 1: numpy's EOFError taken for end of input
    at a prompt), a truncated one a BadZipFile traceback."""
    folder = _corpus(tmp_path, _record("random-3x4/window.npz", 1.0))
    (folder / "random-3x4" / "window.npz").write_bytes(damage((CORPUS / "random-3x4" / "000.npz").read_bytes()))
    result = CliRunner().invoke(app, ["-q", "integrality", "--corpus", str(folder)])
    assert result.exit_code == 2 and said in result.output and "Traceback" not in result.output
    assert "aborted" not in result.output


def test_a_damaged_window_file_is_an_input_error(tmp_path: Path) -> None:
    """Damage inside a member (zlib's error, a bad CRC) is the user's file, not a crash."""
    data = bytearray((CORPUS / "random-3x4" / "000.npz").read_bytes())
    for offset in range(100, len(data) - 200, 97):
        spoiled = bytearray(data)
        spoiled[offset] ^= 0xFF
        path = tmp_path / f"{offset}.npz"
        path.write_bytes(bytes(spoiled))
        try:
            load_window(path)
        except InputError as error:
            assert str(error).startswith(f"{path}: not a markerflow window file") and "\n" not in str(error)
