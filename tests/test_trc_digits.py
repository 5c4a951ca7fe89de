"""A TRC written in cm or m holds the input's values, not the float noise of scaling them to
mm and back: 0.1044258 m was written 0.10442580000000001 (and 104.42580000000001 in cm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_cli import DATA

from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, Recording

WALK = DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc"  # mm, 6 decimals
POSE2SIM = sorted((DATA / "multicam2d_pose2sim_demo").rglob("*.trc"))  # m, 16-17 digits


def _labels(recording: Recording) -> LabeledTrajectories:
    occluded = np.isnan(recording.positions).any(axis=2)
    return LabeledTrajectories(recording.names, recording.positions, occluded, recording.rate)


def _cells(path: Path) -> list[list[str]]:
    return [line.rstrip("\t").split("\t")[2:] for line in path.read_text(encoding="utf-8").splitlines()[6:] if line.strip()]


def _in_unit(path: Path, unit: str, scale: float) -> Path:
    """The walk's first 40 rows in ``unit``, each value as a lab exporter prints it."""
    lines = WALK.read_text(encoding="utf-8").splitlines()
    header, rows = lines[:6], [line for line in lines[6:] if line.strip()][:40]
    header[2] = header[2].replace("\tmm\t", f"\t{unit}\t").replace("\t151\t", "\t40\t")
    values = header[2].split("\t")
    values[2] = "40"
    header[2] = "\t".join(values)
    rows = ["\t".join(cells[:2] + [f"{float(c) / scale:.9f}" if c.strip() else c for c in cells[2:]])
            for cells in (row.split("\t") for row in rows)]
    path.write_text("\n".join(header + rows) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize(("unit", "scale"), [("m", 1000.0), ("cm", 10.0)])
def test_a_trc_in_m_or_cm_is_written_back_with_the_values_it_had(tmp_path: Path, unit: str, scale: float) -> None:
    given = _in_unit(tmp_path / f"in_{unit}.trc", unit, scale)
    recording = read_labeled(given)
    write_labeled(tmp_path / "out.trc", _labels(recording), recording.source)
    written, read = _cells(tmp_path / "out.trc"), _cells(given)
    assert [[float(c) if c else None for c in row] for row in written] == \
        [[float(c) if c.strip() else None for c in row] for row in read]
    assert max(len(c.lstrip("-").replace(".", "").lstrip("0")) for row in written for c in row) <= 15


@pytest.mark.parametrize("path", POSE2SIM, ids=lambda p: p.name)
def test_a_real_trc_in_metres_reads_back_equal(tmp_path: Path, path: Path) -> None:
    recording = read_labeled(path)
    assert recording.source is not None and recording.source.unit == "m"
    write_labeled(tmp_path / "out.trc", _labels(recording), recording.source)
    back = read_labeled(tmp_path / "out.trc")
    assert back.names == recording.names and back.source is not None and back.source.unit == "m"
    np.testing.assert_allclose(back.positions, recording.positions, rtol=1e-9, atol=0)
    np.testing.assert_array_equal(np.isnan(back.positions), np.isnan(recording.positions))


def test_a_trc_in_mm_keeps_every_digit(tmp_path: Path) -> None:
    recording = read_labeled(WALK)
    traj = _labels(recording)
    traj.positions = traj.positions + 1e-9 / 3  # digits past 12 of them
    write_labeled(tmp_path / "out.trc", traj, recording.source)
    np.testing.assert_array_equal(read_labeled(tmp_path / "out.trc").positions, traj.positions)
