"""``markerflow model``'s files: a failed write leaves the earlier model whole and says so in one
line (a full disk cut it to a 4096-byte JSON), and the joint centres keep the take's frame
numbers and times from ``--start`` on, as ``track``'s outputs do (they were numbered from
frame 1, time 0)."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from conftest import DATA
from test_subject_model import chain
from typer.testing import CliRunner

from service.cli.app import app
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, SourceFile

QUALISYS = DATA / "c3d_ezc3d_testfiles" / "Qualisys.c3d"  # first frame 705, 200 Hz
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


def _first_rows(path: Path, rows: int = 2) -> list[list[str]]:
    """Frame number and time of a TRC's or CSV's first rows."""
    lines = path.read_text().splitlines()
    data = lines[6:] if path.suffix == ".trc" else lines[1:]
    return [line.replace(",", "\t").split("\t")[:2] for line in data[:rows]]


@pytest.mark.skipif(not QUALISYS.exists(), reason="needs ../shared/data")
def test_centres_of_a_span_keep_the_takes_numbering_as_track_does(tmp_path: Path) -> None:
    span = ["--start", "20", "--end", "220"]
    tracked = tmp_path / "tracked.trc"
    result = CliRunner().invoke(app, ["-q", "track", str(QUALISYS), "--out", str(tracked), *span])
    assert result.exit_code == 0, result.output
    assert _first_rows(tracked) == [["725", "0.1"], ["726", "0.105"]]
    for suffix in (".trc", ".csv", ".c3d"):
        centres = tmp_path / f"centres{suffix}"
        result = CliRunner().invoke(app, ["-q", "model", str(QUALISYS), "--out", str(tmp_path / "m.json"),
                                          "--centres", str(centres), *span])
        assert result.exit_code == 0, result.output
        if suffix == ".c3d":  # ezc3d counts from 0: frame 725 is 724
            assert ezc3d.c3d(str(centres))["header"]["points"]["first_frame"] == 724
            assert read_labeled(centres).n_frames == 200
        else:
            assert _first_rows(centres) == _first_rows(tracked), suffix


def test_centres_of_a_table_keep_its_own_numbering_and_say_when_takes_follow_on(tmp_path: Path) -> None:
    take = _take(tmp_path / "take.trc", SourceFile(first_frame=100, first_time=2.0))  # frames 101.., 2.0 s..
    centres = tmp_path / "centres.trc"
    args = ["-q", "model", str(take), "--out", str(tmp_path / "m.json"), "--centres", str(centres), "--start", "60"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert _first_rows(centres) == [["161", "2.6"], ["162", "2.61"]]
    assert "numbered on from" not in result.output
    pooled = CliRunner().invoke(app, [*args[:3], str(take), *args[3:]])
    assert pooled.exit_code == 0, pooled.output
    assert ("warning: centres.trc holds the joint centres of the 2 takes one after another, numbered on from "
            "take.trc's frames") in pooled.output
