"""``markerflow track TAKE --model subject.json --start N --keep-labels``: a partly labeled frame
and a subject model together. The input's labels at N are kept (a marker the model cannot
place is labeled from them) and the model names only the markers absent there."""

from __future__ import annotations

import json
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from test_model_output import FIT, FRAMES
from test_subject_model import chain
from typer.testing import CliRunner

from formulations.subject.fit import fit_subject
from service.cli.app import app
from service.io.formats import read_labeled
from service.labeling import capture_labeling


def _take(tmp_path: Path, hide: tuple[int, int] | None = None) -> tuple[Path, Path, list[str], np.ndarray]:
    """A chain of four segments and a stick of two markers, STICK1 and STICK2, 400 mm off the
    chain turning on its own (a mirror-symmetric pair no joint ties to the body: nothing in a
    frame says which end is which); the model is fitted on the first FIT frames.
    ``hide`` (marker, frames) removes that marker's points from FIT for that many frames."""
    names, positions, _ = chain(7, frames=FRAMES)
    t = np.linspace(0, 3, FRAMES)[:, None]
    centre = np.hstack([400 + 60 * np.sin(2 * np.pi * t), 80 * np.cos(2 * np.pi * 1.3 * t), 1100 + 0 * t])
    half = 60 * np.hstack([np.cos(1.5 * t), np.sin(1.5 * t), 0 * t])
    stick = np.stack([centre + half, centre - half], axis=1)
    names, positions = [*names, "STICK1", "STICK2"], np.concatenate([positions, stick], axis=1)
    subject = tmp_path / "subject.json"
    subject.write_text(fit_subject(names, positions[:FIT]).model.to_json())
    given = positions.copy()
    if hide is not None:
        given[FIT: FIT + hide[1], hide[0]] = np.nan
    source = tmp_path / "take.c3d"
    _write(source, names, given)
    return source, subject, names, given


def _write(source: Path, names: list[str], positions: np.ndarray) -> None:
    """A C3D in mm, NaN samples written missing (negative residual)."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = names
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    points = np.ones((4, len(names), len(positions)))
    points[:3] = np.nan_to_num(positions, nan=0.0).transpose(2, 1, 0)
    c3d["data"]["points"] = points
    c3d["data"]["meta_points"]["residuals"] = np.where(np.isnan(positions[..., 0]), -1.0, 0.0).T[None]
    c3d.write(str(source))


def _labeled_right(tmp_path: Path, source: Path, subject: Path, names: list[str], given: np.ndarray,
                   *flags: str) -> np.ndarray:
    """``(frames, markers)`` from --start FIT: the marker holds its own point of the input."""
    out = tmp_path / "out.csv"
    result = CliRunner().invoke(app, ["track", str(source), "--model", str(subject), "--start", str(FIT),
                                      "--out", str(out), *flags])
    assert result.exit_code == 0, result.output
    written = read_labeled(out)
    order = [written.names.index(name) for name in names]
    return np.linalg.norm(written.positions[:, order] - given[FIT:], axis=2) < 0.01


def test_markers_the_model_cannot_tell_apart_are_labeled_from_the_kept_start_frame(tmp_path: Path) -> None:
    source, subject, names, given = _take(tmp_path)
    loose = [names.index("STICK1"), names.index("STICK2")]
    identified = _labeled_right(tmp_path, source, subject, names, given)
    kept = _labeled_right(tmp_path, source, subject, names, given, "--keep-labels")
    assert identified[:, loose].mean() < 0.5
    assert kept[:, loose].mean() > 0.95
    assert kept.mean() > 0.97


def test_a_marker_absent_at_the_start_frame_is_named_by_the_model(tmp_path: Path) -> None:
    hidden, frames = 9, 15
    source, subject, names, given = _take(tmp_path, (hidden, frames))
    kept = _labeled_right(tmp_path, source, subject, names, given, "--keep-labels")
    assert kept[frames + 20:, hidden].mean() > 0.9  # acquired within a window of its return
    assert kept[:, -2:].mean() > 0.95


def test_keep_labels_needs_a_model(tmp_path: Path) -> None:
    source, _, _, _ = _take(tmp_path)
    result = CliRunner().invoke(app, ["track", str(source), "--start", "5", "--out", str(tmp_path / "o.csv"),
                                      "--keep-labels"])
    assert result.exit_code != 0
    assert "--keep-labels" in result.output and "--model" in result.output
    assert "Traceback" not in result.output


def test_labels_the_model_does_not_fit_are_named_in_a_warning(tmp_path: Path) -> None:
    source, subject, names, given = _take(tmp_path)
    out, moved = tmp_path / "out.csv", names.index("S1M2")
    plain = CliRunner().invoke(app, ["track", str(source), "--model", str(subject), "--start", str(FIT),
                                     "--out", str(out), "--keep-labels", "--json"])
    assert plain.exit_code == 0 and '"model_misfits": []' in plain.output
    assert "do not fit" not in plain.output
    replaced = given.copy()
    replaced[:, moved] += np.array([0.0, 80.0, 0.0])  # the lab put S1M2 8 cm from where the model has it
    _write(source, names, replaced)
    warned = CliRunner().invoke(app, ["track", str(source), "--model", str(subject), "--start", str(FIT),
                                      "--out", str(out), "--keep-labels", "--json"])
    assert warned.exit_code == 0, warned.output
    segment = json.loads(next(line for line in warned.output.splitlines() if line.startswith("{")))["model_misfits"]
    assert len(segment) == 1 and segment[0]["off_mm"] > segment[0]["tolerance_mm"]
    assert f"warning: the labels of frame {FIT} do not fit 1 of the model's segments ({segment[0]['segment']} " in warned.output


def test_a_labeled_marker_the_model_lacks_is_labeled_as_its_single(tmp_path: Path) -> None:
    source, subject, names, given = _take(tmp_path)
    extra = given[:, 4] + np.array([0.0, 0.0, 60.0])  # rides on S1; the model was fitted without it
    names, given = [*names, "EXTRA"], np.concatenate([given, extra[:, None]], axis=1)
    _write(source, names, given)
    kept = _labeled_right(tmp_path, source, subject, names, given, "--keep-labels")
    assert kept[:, names.index("EXTRA")].mean() > 0.95
    assert kept.mean() > 0.97


def test_the_take_relearns_the_model_only_when_nothing_is_labeled(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Learning segments from the take is for an identified start; a labeled one places its segments."""
    source, subject, names, given = _take(tmp_path, (9, 15))
    learned: list[int] = []
    monkeypatch.setattr(capture_labeling, "learn_from_take", lambda model, frames: learned.append(1) or model)
    _labeled_right(tmp_path, source, subject, names, given, "--keep-labels")
    assert learned == []
    _labeled_right(tmp_path, source, subject, names, given)
    assert learned == [1]


def test_a_model_that_lumps_segments_does_not_steer_the_kept_labels(tmp_path: Path) -> None:
    """A model fitted where the subject barely moved joins segments the take then bends apart;
    with the labels kept it only names the marker absent at the start (steered, 71 % right)."""
    names, calm, _ = chain(3, frames=200, motion=0.06)
    _, moving, _ = chain(3, frames=300, motion=0.6)  # the same markers, joints turning freely
    model = fit_subject(names, calm).model
    assert sorted(len(s.markers) for s in model.segments) == [8, 8]  # the setup: two segments lumped in each
    subject = tmp_path / "subject.json"
    subject.write_text(model.to_json())
    given, rng = moving.copy(), np.random.default_rng(0)
    for m in rng.choice(len(names), 6, replace=False):
        start = int(rng.integers(20, 260))
        given[start:start + 20, m] = np.nan
    absent = 5
    given[:30, absent] = np.nan
    source, out = tmp_path / "take.c3d", tmp_path / "out.csv"
    _write(source, names, given)
    result = CliRunner().invoke(app, ["track", str(source), "--model", str(subject), "--start", "0", "--keep-labels",
                                      "--out", str(out)])
    assert result.exit_code == 0, result.output
    written = read_labeled(out)
    right = np.linalg.norm(written.positions[:, [written.names.index(n) for n in names]] - given, axis=2) < 0.01
    present = np.isfinite(given).all(axis=2)
    assert right[present].mean() > 0.99
    assert right[present[:, absent], absent].mean() > 0.95
