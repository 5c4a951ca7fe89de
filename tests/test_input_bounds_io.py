"""The marker file readers refuse what no labeling can answer for (an infinite or absurd
coordinate, a marker name twice, a TRC header that disagrees with its columns, rows out of
order) with one line naming it; a take in the wrong unit: ``test_take_scale``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories

NAMES = ["a", "b", "c", "d"]


def take(frames: int = 30, scale: float = 1.0) -> np.ndarray:
    """``(frames, 4, 3)`` mm: four markers 60-100 mm apart walking 10 mm a frame, times ``scale``."""
    corners = np.array([[0.0, 0, 900], [80, 0, 900], [0, 60, 900], [30, 30, 980]])
    walk = np.arange(frames)[:, None, None] * np.array([10.0, 1.0, 0.0])
    return scale * (corners[None] + walk)


def write_c3d(path: Path, positions: np.ndarray, names: list[str] = NAMES, unit: str = "mm") -> Path:
    """A C3D of ``positions`` ``(frames, markers, 3)`` in ``unit``, written by ezc3d itself."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = list(names)
    c3d["parameters"]["POINT"]["UNITS"]["value"] = [unit]
    points = np.ones((4, positions.shape[1], positions.shape[0]))
    points[:3] = positions.transpose(2, 1, 0)
    c3d["data"]["points"] = points
    c3d.write(str(path))
    return path


def write_table(path: Path, positions: np.ndarray, names: list[str] = NAMES) -> Path:
    """A .trc or .csv of ``positions`` as markerflow writes them."""
    frames = len(positions)
    write_labeled(path, LabeledTrajectories(list(names), positions, np.zeros((frames, len(names)), bool), 100.0))
    return path


def edited(path: Path, line: int, old: str, new: str) -> Path:
    lines = path.read_text().splitlines()
    assert old in lines[line], lines[line]
    lines[line] = lines[line].replace(old, new, 1)
    path.write_text("\n".join(lines) + "\n")
    return path


# Non-finite and absurd coordinates: refused, naming marker and frame.

def test_c3d_infinite_sample_is_refused_naming_marker_and_frame(tmp_path):
    positions = take()
    positions[5, 2, 1] = np.inf
    path = write_c3d(tmp_path / "inf.c3d", positions)
    assert np.isinf(ezc3d.c3d(str(path))["data"]["points"][1, 2, 5])  # ezc3d keeps the inf
    with pytest.raises(InputError, match=r"^.*inf\.c3d: marker 'c' has y = inf mm in frame 5$"):
        read_labeled(path)


def test_c3d_beyond_1000_km_is_refused_but_a_large_hall_reads(tmp_path):
    with pytest.raises(InputError, match=r"marker 'a' has z = 1e\+12 mm in frame 0, beyond the 1e\+09 mm"):
        read_labeled(write_c3d(tmp_path / "far.c3d", take(scale=1e12 / 900.0)))
    assert read_labeled(write_c3d(tmp_path / "m.c3d", take() / 1000.0, unit="m")).positions.max() < 2000


@pytest.mark.parametrize("cell", ["inf", "-inf", "1e400"])
def test_trc_infinite_cell_is_refused(tmp_path, cell):
    path = edited(write_table(tmp_path / "t.trc", take()), 9, "\t110.0\t", f"\t{cell}\t")  # frame 3, b's x
    with pytest.raises(InputError, match=r"t\.trc: marker 'b' has x = -?inf mm in frame 3$"):
        read_labeled(path)


def test_trc_nan_cell_stays_a_gap(tmp_path):
    path = edited(write_table(tmp_path / "t.trc", take()), 9, "\t110.0\t", "\tnan\t")
    recording = read_labeled(path)
    assert recording.missing()[3, 1] and recording.missing().sum() == 1


def test_csv_overflowing_cell_is_refused(tmp_path):
    path = edited(write_table(tmp_path / "t.csv", take()), 4, ",110.0,", ",1e400,")
    with pytest.raises(InputError, match=r"t\.csv: marker 'b' has x = inf mm in frame 3$"):
        read_labeled(path)


# Duplicate names: refused as the HTTP service refuses them.

def test_c3d_duplicate_label_is_refused(tmp_path):
    path = write_c3d(tmp_path / "dup.c3d", take(), ["a", "b", "a", "d"])
    with pytest.raises(InputError, match=r"dup\.c3d: marker name 'a' appears twice$"):
        read_labeled(path)


@pytest.mark.parametrize("suffix", [".trc", ".csv"])
def test_table_duplicate_name_is_refused(tmp_path, suffix):
    path = write_table(tmp_path / f"dup{suffix}", take(), ["a", "b", "b", "d"])
    with pytest.raises(InputError, match=r"marker name 'b' appears twice$"):
        read_labeled(path)


def test_cli_refuses_duplicate_names_in_one_line(tmp_path):
    path = write_c3d(tmp_path / "dup.c3d", take(), ["a", "b", "a", "d"])
    run = subprocess.run([sys.executable, "-m", "service.cli", "-q", "track", str(path), "-o", str(tmp_path / "o.trc")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode != 0
    assert run.stderr.strip().splitlines() == [f"error: {path}: marker name 'a' appears twice"]


# TRC headers and row order.

@pytest.mark.parametrize("declared,message", [
    ("2", r"line 4 names 4 markers but the header says NumMarkers 2$"),
    ("5", r"line 4 names 4 markers but the header says NumMarkers 5$"),
    ("3.5", r"TRC header NumMarkers is '3\.5', not a whole number$"),
])
def test_trc_num_markers_must_match_the_names(tmp_path, declared, message):
    path = edited(write_table(tmp_path / "t.trc", take()), 2, "\t4\tmm", f"\t{declared}\tmm")
    with pytest.raises(InputError, match=message):
        read_labeled(path)


def test_trc_fractional_num_frames_is_refused(tmp_path):
    path = edited(write_table(tmp_path / "t.trc", take()), 2, "\t30\t4\t", "\t30.5\t4\t")
    with pytest.raises(InputError, match=r"NumFrames is '30\.5', not a whole number$"):
        read_labeled(path)


def test_trc_rows_out_of_order_are_refused(tmp_path):
    path = write_table(tmp_path / "t.trc", take())
    lines = path.read_text().splitlines()
    lines[10], lines[20] = lines[20], lines[10]  # frames 5 and 15 swapped, Frame# and Time with them
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"t\.trc:12: frame 6 at time 0\.05 does not follow frame 15 at time 0\.14"):
        read_labeled(path)


def test_trc_frame_numbers_may_skip_and_are_written_back(tmp_path):
    path = write_table(tmp_path / "t.trc", take())
    lines = path.read_text().splitlines()
    for i in range(6, len(lines)):  # every other frame of a take at twice the rate
        frame, time, rest = lines[i].split("\t", 2)
        lines[i] = f"{2 * int(frame)}\t{time}\t{rest}"
    path.write_text("\n".join(lines) + "\n")
    back = read_labeled(path)
    np.testing.assert_allclose(back.positions, take())
    assert _numbers(_relabeled(back, tmp_path / "out.trc")) == list(range(2, 61, 2))  # written back as they were


def _relabeled(recording, path: Path) -> list[list[str]]:
    """The table ``path`` written from ``recording`` as its labels, as rows of cells."""
    labels = LabeledTrajectories(recording.names, recording.positions, np.zeros(recording.positions.shape[:2], bool),
                                 recording.rate)
    write_labeled(path, labels, recording.source)
    text = path.read_text().splitlines()
    return [line.split(",") for line in text[1:]] if path.suffix == ".csv" else [line.split("\t") for line in text[6:]]


def _numbers(rows: list[list[str]]) -> list[int]:
    return [int(row[0]) for row in rows]


@pytest.mark.parametrize("suffix", [".csv", ".trc"])
def test_a_table_counting_its_frames_from_0_keeps_them(tmp_path, suffix):
    path = write_table(tmp_path / f"t{suffix}", take())
    first_row = 1 if suffix == ".csv" else 6
    lines = path.read_text().splitlines()
    separator = "," if suffix == ".csv" else "\t"
    for i in range(first_row, len(lines)):
        frame, rest = lines[i].split(separator, 1)
        lines[i] = f"{int(frame) - 1}{separator}{rest}"
    path.write_text("\n".join(lines) + "\n")
    assert _numbers(_relabeled(read_labeled(path), tmp_path / f"out{suffix}")) == list(range(30))


@pytest.mark.parametrize("suffix", [".csv", ".trc"])
@pytest.mark.parametrize(("row", "message"), [
    (12, "frame 12 at time 0.11 does not follow frame 12 at time 0.11; rows must be in order"),  # a row repeated
    (None, "is 0.02 s after the row before, the rows' step is 0.01 s; rows must be evenly spaced in time"),
])
def test_table_rows_repeated_or_unevenly_timed_are_refused(tmp_path, suffix, row, message):
    path = write_table(tmp_path / f"t{suffix}", take())
    first_row = 1 if suffix == ".csv" else 6
    lines = path.read_text().splitlines()
    if row is None:  # frame 15 dropped: its neighbours 0.02 s apart
        del lines[first_row + 14]
    else:
        lines.insert(first_row + row, lines[first_row + row - 1])
    if suffix == ".trc":  # NumFrames as the rows now are
        lines[2] = lines[2].replace("\t30\t", f"\t{len(lines) - first_row}\t", 1)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(".", r"\.")):
        read_labeled(path)


def test_a_decimated_csv_labels_at_its_rows_rate(tmp_path):
    path = write_table(tmp_path / "t.csv", take())
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:1] + lines[1::2]) + "\n")  # frames 1, 3, 5 ... at their own times
    back = read_labeled(path)
    assert back.rate == 50.0 and _numbers(_relabeled(back, tmp_path / "out.csv")) == list(range(1, 30, 2))


def test_trc_values_past_the_named_columns_are_refused_but_trailing_blanks_are_not(tmp_path):
    """A fifth marker's samples with no name in the header used to be dropped without a word."""
    path = write_table(tmp_path / "t.trc", take())
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:6] + [line + "\t\t" for line in lines[6:]]) + "\n")
    assert read_labeled(path).positions.shape == (30, 4, 3)
    path.write_text("\n".join(lines[:6] + [line + "\t1.0\t2.0\t3.0" for line in lines[6:]]) + "\n")
    with pytest.raises(InputError, match=r"t\.trc:7: 3 values past the 4 named markers' columns"):
        read_labeled(path)


@pytest.mark.parametrize("suffix", [".csv", ".trc"])
def test_times_printed_to_3_decimals_at_240_hz_are_even_enough(tmp_path, suffix):
    """Steps of 0.004 and 0.005 s are rounding, not a dropped frame (which doubles a step)."""
    path = write_table(tmp_path / f"t{suffix}", take())
    first_row, separator = (1, ",") if suffix == ".csv" else (6, "\t")
    lines = path.read_text().splitlines()
    for i in range(first_row, len(lines)):
        frame, _, rest = lines[i].split(separator, 2)
        lines[i] = separator.join([frame, f"{(i - first_row) / 240:.3f}", rest])
    path.write_text("\n".join(lines) + "\n")
    assert read_labeled(path).positions.shape == (30, 4, 3)
