"""Labeled output keeps the input: a C3D's analogs, force platforms, events, frame numbering
and unit; TRC out in the input's unit (issue 14, item 4)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from service.errors import InputError
from service.io.formats import check_output, read_labeled, write_labeled
from service.io.formats.trc import read_trc
from service.io.recording import LabeledTrajectories, Recording, SourceFile

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
EZC3D = DATA / "c3d_ezc3d_testfiles"
OPENSIM = DATA / "mocap_opensim"
TENNIS = DATA / "c3d_kineticstoolkit" / "kinematics_tennis_serve.c3d"  # metres
UNITS_FRAMES = 200  # the tennis serve labeled this far: enough samples to tell metres from mm
KEPT_GROUPS = ("ANALOG", "FORCE_PLATFORM", "EVENT", "TRIAL", "SUBJECTS", "MANUFACTURER", "SEG")


def _track(source: Path, out: Path, *flags: str) -> dict:
    result = subprocess.run([sys.executable, "-m", "service.cli", "-q", "track", str(source), "--out", str(out),
                             "--json", *flags], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def _labels(path: Path, frames: int | None = None) -> LabeledTrajectories:
    """The file's own labels as markerflow's answer: every present sample labeled."""
    rec = read_labeled(path)
    positions = rec.positions[:frames]
    return LabeledTrajectories(rec.names, positions, np.isnan(positions).any(axis=2), rec.rate)


def _assert_input_kept(source: Path, out: Path) -> tuple[ezc3d.c3d, ezc3d.c3d]:
    """Everything but the points is the input's: its analog channels byte-equal (the labels'
    confidence channels come after them), parameter groups equal."""
    before, after = ezc3d.c3d(str(source)), ezc3d.c3d(str(out))
    own = before["data"]["analogs"].shape[1]
    assert before["data"]["analogs"].size == 0 or before["data"]["analogs"].dtype == after["data"]["analogs"].dtype
    if own:
        assert np.array_equal(before["data"]["analogs"], after["data"]["analogs"][:, :own])
    added = [str(label).strip() for label in after["parameters"]["ANALOG"]["LABELS"]["value"]][own:]
    assert all(label.endswith("_confidence") for label in added)
    # the input points no marker took come after the input's own, as unlabeled trajectories *N
    points_before, points_after = dict(before["header"]["points"]), dict(after["header"]["points"])
    unlabeled = [str(label) for label in after["parameters"]["POINT"]["LABELS"]["value"]][points_before["size"]:]
    assert all(label.startswith("*") for label in unlabeled)
    assert points_after.pop("size") == points_before.pop("size") + len(unlabeled)
    assert points_before == points_after
    for group in set(KEPT_GROUPS) & set(before["parameters"]):
        for name, parameter in before["parameters"][group].items():
            if name == "__METADATA__" or (group, name) == ("ANALOG", "USED"):
                continue
            if (group, name) == ("ANALOG", "RATE") and own == 0:  # the confidence channels need a rate
                continue
            value, kept = np.asarray(parameter["value"]), np.asarray(after["parameters"][group][name]["value"])
            if group == "ANALOG" and value.ndim == 1 and len(value) == own:  # one entry per channel
                kept = kept[:own]
            assert np.array_equal(value, kept), (group, name)
    for name in ("RATE", "UNITS", "FRAMES"):
        assert np.array_equal(np.asarray(before["parameters"]["POINT"][name]["value"]),
                              np.asarray(after["parameters"]["POINT"][name]["value"])), name
    labels = [str(label) for label in after["parameters"]["POINT"]["LABELS"]["value"]]
    assert labels[: len(labels) - len(unlabeled)] == [str(label) for label in before["parameters"]["POINT"]["LABELS"]["value"]]
    assert int(after["parameters"]["POINT"]["USED"]["value"][0]) == len(labels)
    assert _present_samples(after) == _present_samples(before)  # nothing the input carried is lost
    return before, after


def _present_samples(c3d: ezc3d.c3d) -> int:
    """Samples a C3D holds: residual not negative and not the (0, 0, 0) gap."""
    points, residuals = c3d["data"]["points"][:3], c3d["data"]["meta_points"]["residuals"][0]
    return int(np.sum((residuals >= 0) & np.isfinite(points).all(axis=0) & (points != 0).any(axis=0)))


def _assert_points_where_labeled(before: ezc3d.c3d, after: ezc3d.c3d, labeled: np.ndarray, atol: float) -> None:
    """``labeled`` ``(frames, markers)``: the input's sample there, residual -1 and NaN elsewhere."""
    own = before["header"]["points"]["size"]  # the unlabeled points *N come after the input's
    points = after["data"]["points"][:3, :own].transpose(2, 1, 0)
    residuals = after["data"]["meta_points"]["residuals"][0, :own].T
    np.testing.assert_allclose(points[labeled], before["data"]["points"][:3].transpose(2, 1, 0)[labeled], rtol=0, atol=atol)
    assert (residuals[~labeled] == -1).all() and np.isnan(points[~labeled]).all()
    assert (residuals[labeled] >= 0).all()


def _assert_input_samples(labeled: np.ndarray, inputs: np.ndarray, atol: float) -> None:
    """Each labeled ``(frames, markers, 3)`` sample is one of the input's samples in its frame (the point
    the marker took, right or wrong), in the same unit: NaN (unlabeled) samples aside."""
    distance = np.linalg.norm(labeled[:, :, None] - inputs[:, None], axis=3)
    nearest = np.nanmin(np.where(np.isnan(distance), np.inf, distance), axis=2)
    seen = ~np.isnan(labeled).any(axis=2)
    assert seen.mean() > 0.9 and (nearest[seen] <= atol).all()


def test_vicon_tracked_to_c3d_keeps_its_38_analog_channels(tmp_path: Path) -> None:
    source = EZC3D / "Vicon.c3d"
    summary = _track(source, tmp_path / "x.c3d")
    before, after = _assert_input_kept(source, tmp_path / "x.c3d")
    assert before["data"]["analogs"].shape[1] == 38 and "SUBJECTS" in after["parameters"]
    labeled = ~read_labeled(source).missing()  # markerflow found every marker where the input has it
    _assert_points_where_labeled(before, after, labeled, atol=1e-4)
    assert summary["occluded_fraction"] == pytest.approx(1 - labeled.mean())


def test_bts_labels_of_a_span_leave_the_other_frames_present_and_unlabeled(tmp_path: Path) -> None:
    """BTS.c3d has every marker only from frame 401 on: labels of frames 401.. are placed there."""
    source = EZC3D / "BTS.c3d"
    rec = read_labeled(source)
    span = _labels(source)
    span = LabeledTrajectories(span.names, span.positions[401:], span.occluded[401:], span.rate)
    write_labeled(tmp_path / "x.c3d", span, rec.source, start=401)
    before, after = _assert_input_kept(source, tmp_path / "x.c3d")
    assert before["data"]["analogs"].shape[1] == 44 and after["parameters"]["FORCE_PLATFORM"]["USED"]["value"][0] == 6
    labeled = ~rec.missing()
    labeled[:401] = False
    _assert_points_where_labeled(before, after, labeled, atol=1e-4)


def test_qualisys_tracked_keeps_its_events_force_plates_and_first_frame_number(tmp_path: Path) -> None:
    source = EZC3D / "Qualisys.c3d"
    _track(source, tmp_path / "x.c3d")
    before, after = _assert_input_kept(source, tmp_path / "x.c3d")
    assert after["header"]["points"]["first_frame"] == 704
    event, plates = after["parameters"]["EVENT"], after["parameters"]["FORCE_PLATFORM"]
    assert (event["USED"]["value"][0], len(event["LABELS"]["value"]), plates["USED"]["value"][0]) == (7, 7, 2)
    _assert_points_where_labeled(before, after, ~read_labeled(source).missing(), atol=1e-4)


def test_tables_are_numbered_from_the_inputs_first_frame(tmp_path: Path) -> None:
    source = EZC3D / "Qualisys.c3d"
    rec = read_labeled(source)
    assert rec.source is not None and rec.source.first_frame == 704
    write_labeled(tmp_path / "x.trc", _labels(source), rec.source)
    rows = (tmp_path / "x.trc").read_text().splitlines()[6:]
    assert rows[0].split("\t")[:2] == ["705", "0.0"] and rows[-1].split("\t")[0] == str(705 + rec.n_frames - 1)
    write_labeled(tmp_path / "x.csv", _labels(source), rec.source, start=0)
    csv_rows = (tmp_path / "x.csv").read_text().splitlines()[1:]
    assert csv_rows[0].split(",")[:2] == ["705", "0.0"]  # the same numbers as the TRC's
    back = read_labeled(tmp_path / "x.csv")
    assert back.rate == rec.rate and back.source is not None and back.source.first_frame == 704
    write_labeled(tmp_path / "y.trc", _labels(source), back.source)  # a CSV relabeled keeps its numbering
    assert (tmp_path / "y.trc").read_text().splitlines()[6].split("\t")[:2] == ["705", "0.0"]


def test_a_trc_starting_past_frame_1_keeps_its_frame_numbers_and_times(tmp_path: Path) -> None:
    """rajagopal's run starts at Frame# 23, Time 0.23: relabeled from frame 10, its rows
    must say 33 and 0.33, not 11 and 0.1."""
    source = OPENSIM / "rajagopal_motion_capture_run.trc"
    rec = read_labeled(source)
    first = source.read_text().splitlines()[6].split("\t")[:2]
    assert [float(cell) for cell in first] == [23, 0.23] and rec.source is not None
    labels = _labels(source)
    for name in ("x.trc", "x.csv"):
        write_labeled(tmp_path / name, replace(labels, positions=labels.positions[10:], occluded=labels.occluded[10:]),
                      rec.source, start=10)
    row = (tmp_path / "x.trc").read_text().splitlines()[6].split("\t")
    assert int(row[0]) == 33 and float(row[1]) == pytest.approx(0.33)
    row = (tmp_path / "x.csv").read_text().splitlines()[1].split(",")
    assert int(row[0]) == 33 and float(row[1]) == pytest.approx(0.33)


def test_tennis_in_metres_stays_in_metres(tmp_path: Path) -> None:
    """Its first ``UNITS_FRAMES`` labeled (units need no more), the file written whole."""
    _track(TENNIS, tmp_path / "x.c3d", "--end", str(UNITS_FRAMES))
    before, after = _assert_input_kept(TENNIS, tmp_path / "x.c3d")
    assert after["parameters"]["POINT"]["UNITS"]["value"] == ["m"]
    # In metres: a mm value written unconverted would be off by a factor of 1000.
    points = after["data"]["points"][:3].transpose(2, 1, 0)  # the labeled points, then the unlabeled *N
    labeled = points[:UNITS_FRAMES, : before["header"]["points"]["size"]]
    _assert_input_samples(labeled, before["data"]["points"][:3].transpose(2, 1, 0)[:UNITS_FRAMES], atol=1e-9)
    assert (after["data"]["meta_points"]["residuals"][0].T[np.isnan(points).any(axis=2)] == -1).all()


def test_trc_out_of_a_c3d_in_metres_reads_back_in_metres(tmp_path: Path) -> None:
    summary = _track(TENNIS, tmp_path / "x.trc")
    assert summary["output"] == str(tmp_path / "x.trc")
    text = (tmp_path / "x.trc").read_text().splitlines()
    assert text[2].split("\t")[4] == "m"
    back, truth = read_trc(tmp_path / "x.trc"), read_labeled(TENNIS)
    assert back.names == truth.names and back.rate == truth.rate and back.n_frames == truth.n_frames
    _assert_input_samples(back.positions, truth.positions, atol=1e-9)


@pytest.mark.parametrize("unit", ["mm", "cm", "m"])
def test_trc_round_trip_in_each_unit(unit: str, tmp_path: Path) -> None:
    traj = _labels(EZC3D / "Qualisys.c3d", frames=30)
    traj.occluded[3, 5] = True
    traj.positions[3, 5] = np.nan
    write_labeled(tmp_path / "x.trc", traj, SourceFile(unit=unit))
    back = read_labeled(tmp_path / "x.trc")
    assert back.names == traj.names and back.rate == traj.rate and back.source == SourceFile(unit=unit)
    assert np.array_equal(np.isnan(back.positions).any(axis=2), traj.occluded)
    np.testing.assert_allclose(back.positions[~traj.occluded], traj.positions[~traj.occluded], rtol=1e-12)


def test_trc_input_gives_trc_output_in_its_unit(tmp_path: Path) -> None:
    walk = DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc"
    rec = read_labeled(walk)
    unit = rec.source.unit if rec.source else None
    write_labeled(tmp_path / "x.trc", LabeledTrajectories(rec.names, rec.positions, rec.missing(), rec.rate), rec.source)
    assert (tmp_path / "x.trc").read_text().splitlines()[2].split("\t")[4] == unit
    back = read_labeled(tmp_path / "x.trc")
    seen = ~rec.missing()
    np.testing.assert_allclose(back.positions[seen], rec.positions[seen], rtol=1e-12)


def test_output_that_does_not_fit_the_input_is_refused(tmp_path: Path) -> None:
    rec = read_labeled(EZC3D / "Qualisys.c3d")
    traj = _labels(EZC3D / "Qualisys.c3d")
    renamed = LabeledTrajectories(["nobody"] + traj.names[1:], traj.positions, traj.occluded, traj.rate)
    with pytest.raises(InputError, match="no point named 'nobody'"):
        write_labeled(tmp_path / "x.c3d", renamed, rec.source)
    with pytest.raises(InputError, match="do not fit"):
        write_labeled(tmp_path / "x.c3d", traj, rec.source, start=1)


def test_labels_without_a_source_are_a_new_c3d_in_mm(tmp_path: Path) -> None:
    built = Recording(["a", "b"], np.arange(12.0).reshape(2, 2, 3) + 1, 100.0)
    assert built.source is None
    traj = LabeledTrajectories(built.names, built.positions, np.zeros((2, 2), bool), built.rate)
    write_labeled(tmp_path / "x.c3d", traj)
    back = read_labeled(tmp_path / "x.c3d")
    assert back.source is not None and (back.source.unit, back.source.first_frame) == ("mm", 0)
    assert np.array_equal(back.positions, built.positions)


def test_check_output_accepts_trc(tmp_path: Path) -> None:
    check_output(tmp_path / "x.trc")
    with pytest.raises(InputError, match=r"\.c3d, \.trc, \.csv"):
        check_output(tmp_path / "x.txt")
