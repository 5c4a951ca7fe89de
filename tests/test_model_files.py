"""``markerflow model``'s files: a failed write leaves the earlier model whole and says so in one
line (a full disk cut it to a 4096-byte JSON)."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest
from test_subject_model import chain
from typer.testing import CliRunner

from service.cli.app import app
from service.io.formats import write_labeled
from service.io.recording import LabeledTrajectories, SourceFile

EARLIER = '{"earlier": "model"}'


def _take(path: Path, source: SourceFile | None = None) -> Path:
    names, positions, _ = chain(3)
    write_labeled(path, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0), source)
    return path


def _disk_full_at(suffix: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """``Path.write_text`` to a file ending ``suffix`` writes half its text, then the disk is full."""
    write_text = Path.write_text

    def full(self: Path, data: str, *args: object, **kwargs: object) -> int:
        if not self.name.endswith(suffix):
            return write_text(self, data, *args, **kwargs)  # type: ignore[arg-type]
        write_text(self, data[: len(data) // 2])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Path, "write_text", full)


def _errors(output: str) -> list[str]:
    assert "Traceback" not in output
    return [line for line in output.splitlines() if line.startswith("error:")]


def test_a_full_disk_leaves_the_earlier_model_whole_and_says_so(tmp_path: Path, monkeypatch) -> None:
    take, model = _take(tmp_path / "take.trc"), tmp_path / "model.json"
    model.write_text(EARLIER)
    _disk_full_at(".json", monkeypatch)
    result = CliRunner().invoke(app, ["-q", "model", str(take), "--out", str(model)])
    assert result.exit_code == 2, result.output
    assert _errors(result.output) == [f"error: {model}: cannot write (No space left on device); any earlier file "
                                      "there is untouched"]
    assert model.read_text() == EARLIER and sorted(os.listdir(tmp_path)) == ["model.json", "take.trc"]


def test_a_failed_centres_write_says_the_model_was_written(tmp_path: Path, monkeypatch) -> None:
    take, model, centres = _take(tmp_path / "take.csv"), tmp_path / "model.json", tmp_path / "centres.trc"
    centres.write_text("earlier centres")
    _disk_full_at(".trc", monkeypatch)
    result = CliRunner().invoke(app, ["-q", "model", str(take), "--out", str(model), "--centres", str(centres)])
    assert result.exit_code == 2, result.output
    assert _errors(result.output) == [f"error: {centres}: cannot write (No space left on device); any earlier file "
                                      f"there is untouched; the model was written to {model}"]
    assert centres.read_text() == "earlier centres" and '"version"' in model.read_text()
