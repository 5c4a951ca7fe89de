"""Reading and writing marker files, checked against real recordings and raw ezc3d."""

from __future__ import annotations

import struct
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.formats.c3d import read_c3d, write_c3d
from service.io.formats.csv import read_csv_labeled, write_csv
from service.io.formats.trc import read_trc
from service.io.recording import LabeledTrajectories

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
CMU = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
ROLLING = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "03_rolling.c3d"
METRES = DATA / "c3d_kineticstoolkit" / "kinematics_tennis_serve.c3d"
WALK_TRC = DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc"
ALL_C3D = sorted(DATA.glob("*/*.c3d"))
ALL_TRC = sorted(DATA.glob("mocap_opensim/*.trc"))


def _raw_points(path: Path) -> np.ndarray:
    """``(frames, markers, 3)`` straight from ezc3d, in the file's own unit."""
    return ezc3d.c3d(str(path))["data"]["points"][:3].transpose(2, 1, 0)


def _occluded_cmu(frames: int = 810) -> LabeledTrajectories:
    """85_02 with a block, a stripe and one single sample marked occluded."""
    rec = read_c3d(CMU)
    occluded = np.zeros((rec.n_frames, rec.n_markers), dtype=bool)
    occluded[100:130, 10] = True
    occluded[::7, 3] = True
    occluded[0, 0] = True
    positions = np.where(occluded[..., None], np.nan, rec.positions)
    return LabeledTrajectories(rec.names, positions[:frames], occluded[:frames], rec.rate)


def _assert_matches(positions: np.ndarray, traj: LabeledTrajectories, atol: float) -> None:
    assert np.array_equal(np.isnan(positions).any(axis=2), traj.occluded)
    seen = ~traj.occluded
    np.testing.assert_allclose(positions[seen], traj.positions[seen], rtol=0, atol=atol)


def test_c3d_round_trip_read_back_with_raw_ezc3d(tmp_path: Path) -> None:
    traj = _occluded_cmu()
    out = tmp_path / "labels.c3d"
    write_c3d(out, traj)
    raw = ezc3d.c3d(str(out))
    assert raw["parameters"]["POINT"]["LABELS"]["value"] == traj.names
    assert raw["parameters"]["POINT"]["UNITS"]["value"] == ["mm"]
    assert raw["header"]["points"]["frame_rate"] == pytest.approx(120.0)
    assert raw["data"]["points"].shape == (4, 41, 810)
    _assert_matches(raw["data"]["points"][:3].transpose(2, 1, 0), traj, atol=1e-3)


def test_c3d_round_trip_read_back_with_read_c3d(tmp_path: Path) -> None:
    traj = _occluded_cmu()
    out = tmp_path / "labels.c3d"
    write_c3d(out, traj)
    rec = read_c3d(out)
    assert rec.names == traj.names
    assert rec.rate == pytest.approx(traj.rate)
    _assert_matches(rec.positions, traj, atol=1e-3)


def test_c3d_cmu_file_matches_raw_ezc3d() -> None:
    rec = read_c3d(CMU)
    assert (rec.n_frames, rec.n_markers, rec.rate) == (810, 41, 120.0)
    assert rec.names[0] == "Male:LFWT"
    np.testing.assert_array_equal(rec.positions, _raw_points(CMU))


def test_c3d_in_metres_is_converted_to_millimetres() -> None:
    rec = read_c3d(METRES)
    raw = _raw_points(METRES)
    assert ezc3d.c3d(str(METRES))["parameters"]["POINT"]["UNITS"]["value"] == ["m"]
    np.testing.assert_allclose(rec.positions, raw * 1000.0)
    # A person measured in mm spans hundreds to thousands, not single digits.
    assert 500.0 < np.nanmax(np.abs(rec.positions)) < 10_000.0
    assert np.nanmax(np.abs(raw)) < 10.0


def test_c3d_zero_samples_become_nan() -> None:
    raw_zero = (_raw_points(ROLLING) == 0).all(axis=2)
    assert raw_zero.mean() == pytest.approx(0.229, abs=0.001)  # README's measured share
    rec = read_c3d(ROLLING)
    assert np.array_equal(np.isnan(rec.positions).any(axis=2), raw_zero)
    assert not (rec.positions == 0).all(axis=2).any()


@pytest.mark.parametrize("path", ALL_C3D, ids=lambda p: p.name)
def test_every_real_c3d_file_reads_whole(path: Path) -> None:
    rec = read_c3d(path)
    raw = ezc3d.c3d(str(path))
    assert rec.n_frames == raw["data"]["points"].shape[2] > 0
    assert rec.names == raw["parameters"]["POINT"]["LABELS"]["value"]


def _trc_header(path: Path) -> dict[str, str]:
    lines = path.read_text().splitlines()
    return dict(zip(lines[1].split("\t"), [v.strip() for v in lines[2].split("\t")]))


@pytest.mark.parametrize("path", ALL_TRC, ids=lambda p: p.name)
def test_trc_matches_its_header(path: Path) -> None:
    header = _trc_header(path)
    rec = read_trc(path)
    assert rec.n_frames == int(header["NumFrames"])
    assert rec.n_markers == int(header["NumMarkers"])
    assert rec.rate == float(header["DataRate"])


def test_trc_values_equal_the_raw_text_cells() -> None:
    lines = WALK_TRC.read_text().splitlines()
    rec = read_trc(WALK_TRC)
    assert rec.names[:2] == ["R.ASIS", "L.ASIS"]
    assert rec.names[-1] == lines[3].split("\t")[2 + 3 * 40]
    first, last = lines[6].split("\t"), lines[-1].split("\t")
    assert rec.positions[0, 0, 0] == float(first[2]) == 617.24762
    assert rec.positions[0, 1, 2] == float(first[7])
    assert rec.positions[-1, 40, 1] == float(last[2 + 3 * 40 + 1])


def test_trc_marker_written_as_zeros_becomes_nan() -> None:
    rec = read_trc(DATA / "mocap_opensim" / "hamner_subject02_running.trc")
    never_seen = np.isnan(rec.positions).all(axis=(0, 2))
    assert never_seen.sum() == 1


def test_csv_round_trip(tmp_path: Path) -> None:
    traj = _occluded_cmu(frames=150)
    out = tmp_path / "labels.csv"
    write_csv(out, traj)
    lines = out.read_text().splitlines()
    assert lines[0].startswith("frame,time,Male:LFWT_x,Male:LFWT_y,Male:LFWT_z,Male:RFWT_x")
    assert lines[1].startswith("1,0.0,,,,")  # frame 1 (counted from 1), marker 0 occluded
    back = read_csv_labeled(out)
    assert back.names == traj.names
    assert back.rate == pytest.approx(traj.rate, rel=1e-12)
    _assert_matches(back.positions, traj, atol=0.0)


def test_csv_sample_with_any_blank_cell_is_occluded(tmp_path: Path) -> None:
    out = tmp_path / "partial.csv"
    write_csv(out, _occluded_cmu(frames=3))
    lines = out.read_text().splitlines()
    cells = lines[2].split(",")
    cells[2 + 3 * 5 + 1] = ""  # frame 1, marker 5: y only
    lines[2] = ",".join(cells)
    out.write_text("\n".join(lines) + "\n")
    back = read_csv_labeled(out)
    assert back.occluded[1, 5]
    assert np.isnan(back.positions[1, 5]).all()
    assert back.occluded.sum() == 3  # the two from _occluded_cmu plus this one


def test_dispatch_by_suffix(tmp_path: Path) -> None:
    assert read_labeled(CMU).n_markers == 41
    assert read_labeled(WALK_TRC).n_frames == 151
    traj = _occluded_cmu(frames=20)
    write_labeled(tmp_path / "a.c3d", traj)
    write_labeled(tmp_path / "a.csv", traj)
    assert read_c3d(tmp_path / "a.c3d").n_frames == 20
    assert read_csv_labeled(tmp_path / "a.csv").n_frames == 20
    relabel = read_labeled(tmp_path / "a.csv")  # a CSV markerflow wrote is a labeled input too
    assert relabel.names == traj.names and relabel.rate == pytest.approx(traj.rate, rel=1e-12)
    _assert_matches(relabel.positions, traj, atol=0.0)


def _cut(src: Path, dst: Path, n_bytes: int) -> Path:
    dst.write_bytes(src.read_bytes()[:n_bytes])
    return dst


def _zero_frame_c3d(dst: Path) -> Path:
    """85_02 declaring zero frames (last frame 0) and cut where its data would start."""
    data = bytearray(CMU.read_bytes())
    struct.pack_into("<H", data, 8, 0)
    (data_start,) = struct.unpack_from("<H", data, 16)
    dst.write_bytes(data[: (data_start - 1) * 512])
    return dst


def _c3d_without_points(dst: Path) -> Path:
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["data"]["points"] = np.ones((4, 0, 5))
    c3d.write(str(dst))
    return dst


def _c3d_in_inches(dst: Path) -> Path:
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ["a"]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["in"]
    c3d["data"]["points"] = np.ones((4, 1, 5))
    c3d.write(str(dst))
    return dst


def _trc_edit(dst: Path, line: int, old: str, new: str) -> Path:
    lines = WALK_TRC.read_text().splitlines()
    assert old in lines[line]
    lines[line] = lines[line].replace(old, new, 1)
    dst.write_text("\n".join(lines) + "\n")
    return dst


def _trc_without_last_row(dst: Path) -> Path:
    dst.write_text("\n".join(WALK_TRC.read_text().splitlines()[:-1]) + "\n")
    return dst


def _directory(dst: Path) -> Path:
    dst.mkdir()  # ezc3d would hang reading a directory
    return dst


ERROR_CASES = {
    "c3d missing": lambda d: (read_c3d, d / "absent.c3d"),
    "c3d is a directory": lambda d: (read_c3d, _directory(d / "folder.c3d")),
    "c3d half cut": lambda d: (read_c3d, _cut(CMU, d / "half.c3d", CMU.stat().st_size // 2)),
    "c3d cut at data": lambda d: (read_c3d, _cut(CMU, d / "nodata.c3d", 18 * 512)),
    "c3d cut in parameters": lambda d: (read_c3d, _cut(CMU, d / "params.c3d", 5000)),
    "c3d cut in header": lambda d: (read_c3d, _cut(CMU, d / "header.c3d", 300)),
    "c3d empty": lambda d: (read_c3d, _cut(CMU, d / "empty.c3d", 0)),
    "c3d is text": lambda d: (read_c3d, _cut(WALK_TRC, d / "text.c3d", 4000)),
    "c3d zero frames": lambda d: (read_c3d, _zero_frame_c3d(d / "zero.c3d")),
    "c3d no points": lambda d: (read_c3d, _c3d_without_points(d / "nopoints.c3d")),
    "c3d inches": lambda d: (read_c3d, _c3d_in_inches(d / "inches.c3d")),
    "trc missing": lambda d: (read_trc, d / "absent.trc"),
    "trc is c3d": lambda d: (read_trc, _cut(CMU, d / "binary.trc", 20_000)),
    "trc bad cell": lambda d: (read_trc, _trc_edit(d / "cell.trc", 6, "617.247620", "6l7.2")),
    "trc no units": lambda d: (read_trc, _trc_edit(d / "units.trc", 1, "Units", "Unit")),
    "trc bad rate": lambda d: (read_trc, _trc_edit(d / "rate.trc", 2, "60.00", "fast")),
    "trc few names": lambda d: (read_trc, _trc_edit(d / "names.trc", 2, "\t41\t", "\t42\t")),
    "trc rows short": lambda d: (read_trc, _trc_without_last_row(d / "rows.trc")),
    "trc header only": lambda d: (read_trc, _cut(WALK_TRC, d / "head.trc", 40)),
    "csv missing": lambda d: (read_csv_labeled, d / "absent.csv"),
    "csv bad header": lambda d: (read_csv_labeled, _cut(WALK_TRC, d / "header.csv", 4000)),
    "read suffix": lambda d: (read_labeled, _cut(CMU, d / "labels.xyz", 100)),
}


@pytest.mark.parametrize("case", ERROR_CASES, ids=str)
def test_bad_input_raises_one_line_input_error_naming_the_file(
    case: str, tmp_path: Path
) -> None:
    reader, path = ERROR_CASES[case](tmp_path)
    with pytest.raises(InputError) as caught:
        reader(path)
    message = str(caught.value)
    assert path.name in message
    assert "\n" not in message


def _csv_edit(dst: Path, old: str, new: str) -> Path:
    write_csv(dst, _occluded_cmu(frames=3))
    text = dst.read_text()
    assert old in text
    dst.write_text(text.replace(old, new, 1))
    return dst


@pytest.mark.parametrize(
    ("old", "new"),
    [("1,0.0,", "1,zero,"), ("\n3,", "\n3,1,"), ("\n3,0.016666666666666666,", "\n3,0.0,")],
    ids=["non-numeric", "ragged", "no rate"],
)
def test_bad_csv_cells_raise_input_error(old: str, new: str, tmp_path: Path) -> None:
    path = _csv_edit(tmp_path / "cells.csv", old, new)
    with pytest.raises(InputError, match="cells.csv"):
        read_csv_labeled(path)
