"""Marker names at the edge of what a C3D holds, and names no output carries back.

A name of 245 to 255 bytes made ``track --out X.c3d`` exit 0 with a file no reader opens: its
confidence channel ``<name>_confidence`` passed the 255 bytes of a C3D label. And a TRC or
CSV name with a NUL or another control character was written (``L.ASIS\\x00x`` came back
``L.ASISx`` from the C3D); such names are refused as the capture JSON refuses them.
"""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest
from test_cli import assert_input_error, run_cli

from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.formats.c3d import read_c3d
from service.io.recording import LabeledTrajectories
from tests.test_formats import _occluded_cmu

LONG = ["a" * 245, "a" * 250, "é" * 127 + "x", "a" * 242 + "~3"]  # 245, 250, 255 and 244 bytes


def _labels(names: list[str], frames: int = 6) -> LabeledTrajectories:
    base = _occluded_cmu(frames=frames)
    traj = LabeledTrajectories(names + base.names[len(names):], base.positions, base.occluded, base.rate)
    traj.confidence = np.linspace(0.2, 0.9, frames * len(traj.names)).reshape(frames, len(traj.names))
    return traj


def _channels(path: Path) -> tuple[list[str], list[str], np.ndarray]:
    raw = ezc3d.c3d(str(path))  # raises on a label over 255 bytes: "The format is not standard"
    analog = raw["parameters"]["ANALOG"]
    return list(analog["LABELS"]["value"]), list(analog["DESCRIPTIONS"]["value"]), raw["data"]["analogs"][0]


def test_a_c3d_of_names_too_long_for_their_confidence_suffix_reads_back(tmp_path: Path) -> None:
    traj = _labels(LONG)
    write_labeled(tmp_path / "long.c3d", traj)
    labels, descriptions, values = _channels(tmp_path / "long.c3d")
    assert read_c3d(tmp_path / "long.c3d").names == traj.names
    assert all(len(label.encode()) <= 255 for label in labels) and len(set(labels)) == len(labels)
    assert labels[3] == LONG[3] + "_confidence"  # fits whole; the 250-byte name cut to its spelling is not it
    assert labels[1] != labels[3] and labels[1].endswith("_confidence")
    assert labels[4:] == [f"{name}_confidence" for name in traj.names[4:]]
    for i in range(3):  # cut, and their descriptions name the point
        assert descriptions[i].startswith(f"markerflow label confidence of point {i + 1} ({traj.names[i][:20]}")
    assert descriptions[4] == "markerflow label confidence"
    np.testing.assert_allclose(values, traj.confidence.T, atol=1e-6)


def test_relabeling_such_a_c3d_replaces_its_cut_channels(tmp_path: Path) -> None:
    write_labeled(tmp_path / "first.c3d", _labels(LONG))
    again = read_labeled(tmp_path / "first.c3d")
    traj = _labels(LONG)
    traj.confidence = np.full_like(traj.confidence, 0.5)
    write_labeled(tmp_path / "again.c3d", traj, again.source)
    labels, _, values = _channels(tmp_path / "again.c3d")
    assert len(labels) == len(traj.names)  # replaced, not added a second time
    np.testing.assert_allclose(values, 0.5, atol=1e-6)


def test_write_labeled_refuses_for_a_table_the_names_its_reader_refuses(tmp_path: Path) -> None:
    traj = _labels(["L.ASIS\x00x"])
    for suffix in (".trc", ".csv"):
        with pytest.raises(InputError, match=rf"out{suffix}: marker name 'L.ASIS\\x00x' has a control character"):
            write_labeled(tmp_path / f"out{suffix}", traj)
    assert not list(tmp_path.iterdir())


def test_track_from_a_trc_with_a_250_byte_name_writes_a_readable_c3d(tmp_path: Path) -> None:
    traj = _labels(["R" * 250], frames=12)
    write_labeled(tmp_path / "long.trc", LabeledTrajectories(traj.names, traj.positions, traj.occluded, traj.rate))
    result = run_cli("-q", "track", tmp_path / "long.trc", "--out", tmp_path / "out.c3d", "--start", "1")
    assert result.returncode == 0, result.stderr
    labels, _, _ = _channels(tmp_path / "out.c3d")
    assert all(len(label.encode()) <= 255 for label in labels) and len(labels) == len(traj.names)


def _table(path: Path, names: list[str]) -> Path:
    """A table with ``names`` first, as another program wrote it (``write_labeled`` refuses
    the names its readers refuse)."""
    base = _occluded_cmu(frames=5)
    stand_ins = [f"NAME{i}" for i in range(len(names))]
    write_labeled(path, LabeledTrajectories(stand_ins + base.names[len(names):], base.positions, base.occluded,
                                            base.rate))
    text = path.read_text(encoding="utf-8")
    for stand_in, name in zip(stand_ins, names, strict=True):
        text = text.replace(stand_in, name)
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("suffix", [".trc", ".csv"])
@pytest.mark.parametrize(("name", "problem"), [
    ("L.ASIS\x00x", "has a control character"),
    ("L.ASIS\x01", "has a control character"),
    ("R" * 256, "is longer than 255 bytes"),
])
def test_a_table_name_no_output_carries_back_is_refused(tmp_path: Path, suffix: str, name: str, problem: str) -> None:
    path = _table(tmp_path / f"take{suffix}", [name])
    assert name in path.read_text(encoding="utf-8")
    with pytest.raises(InputError, match=rf"take{suffix}: marker name '.*'(\.\.\.)? {problem}"):
        read_labeled(path)


def test_track_names_a_nul_in_a_trc_in_one_line(tmp_path: Path) -> None:
    path = _table(tmp_path / "nul.trc", ["L.ASIS\x00x"])
    assert_input_error(run_cli("track", path, "--out", tmp_path / "out.c3d"), "nul.trc", "L.ASIS\\x00x",
                       "control character")


@pytest.mark.parametrize("suffix", [".trc", ".csv"])
def test_unlabeled_trajectory_columns_and_255_byte_names_are_still_read(tmp_path: Path, suffix: str) -> None:
    names = ["*0", "é" * 127 + "x"]
    assert read_labeled(_table(tmp_path / f"take{suffix}", names)).names[:2] == names
