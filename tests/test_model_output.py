"""``markerflow track IN.c3d --model subject.json --start N --out OUT.c3d`` keeps what the input
carried: its frame numbering, point rate and length unit, its analog channels and parameter
groups, and the samples of points the model does not name; the model's points hold the
labels from frame N on (the input's own samples, since the labels are right) and are missing
before. Checked with ezc3d on the written file, not with markerflow's reader."""

from __future__ import annotations

import json
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from conftest import DATA
from test_subject_model import chain
from typer.testing import CliRunner

from formulations.subject.fit import fit_subject
from service.cli.app import app
from service.io.formats import read_labeled

FIT, FRAMES = 250, 300
FIRST = 37  # the input's first frame number
CMU_85_02 = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def _input_c3d(path: Path, names: list[str], metres: np.ndarray) -> None:
    """A C3D in metres, numbered from FIRST, with two analog channels at twice the point rate,
    a point the model does not know (``EXTRA``) and a parameter group of the lab's own."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = names
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
    c3d["header"]["points"]["first_frame"] = FIRST
    points = np.ones((4, len(names), len(metres)))
    points[:3] = metres.transpose(2, 1, 0)
    c3d["data"]["points"] = points
    c3d["data"]["meta_points"]["residuals"] = np.zeros((1, len(names), len(metres)))
    c3d["parameters"]["ANALOG"]["RATE"]["value"] = np.array([200.0])
    c3d["parameters"]["ANALOG"]["LABELS"]["value"] = ["EMG1", "FZ"]
    c3d["parameters"]["ANALOG"]["UNITS"]["value"] = ["V", "N"]
    c3d["data"]["analogs"] = np.random.default_rng(1).normal(0, 1, (1, 2, 2 * len(metres)))
    c3d.add_parameter("LAB", "SESSION", ["pre-op"])
    c3d.write(str(path))


def _track(tmp_path: Path, source: Path, model_json: str, start: int, end: int | None = None) -> tuple[Path, str]:
    """The output and what the command printed (stdout, then stderr)."""
    subject, out = tmp_path / "subject.json", tmp_path / "out.c3d"
    subject.write_text(model_json)
    span = ["--end", str(end)] if end is not None else []
    result = CliRunner().invoke(app, ["track", str(source), "--model", str(subject), "--start", str(start),
                                      "--out", str(out), *span])
    assert result.exit_code == 0, result.output
    return out, result.output


def test_output_keeps_the_inputs_numbering_unit_analogs_and_parameters(tmp_path: Path) -> None:
    names, positions, _ = chain(7, frames=FRAMES)
    model = fit_subject(names, positions[:FIT]).model
    extra = positions[:, :1] + np.array([0.0, 0.0, 150.0])  # rides along, unknown to the model
    source = tmp_path / "take.c3d"
    _input_c3d(source, [*names, "EXTRA"], np.concatenate([positions, extra], axis=1) / 1000)
    out, printed = _track(tmp_path, source, model.to_json(), FIT)
    given, written = ezc3d.c3d(str(source)), ezc3d.c3d(str(out))
    assert "is a new C3D of the labels" not in printed

    assert written["header"]["points"]["first_frame"] == FIRST
    own = given["data"]["points"].shape[1]  # the input's points, then its samples before --start, unlabeled (*N)
    assert written["data"]["points"][:, :own].shape == given["data"]["points"].shape
    assert list(written["parameters"]["POINT"]["UNITS"]["value"]) == ["m"]
    assert written["parameters"]["POINT"]["RATE"]["value"][0] == 100.0
    assert written["parameters"]["LAB"]["SESSION"]["value"] == ["pre-op"]
    labels = [str(label).strip() for label in written["parameters"]["ANALOG"]["LABELS"]["value"]]
    assert labels[:2] == ["EMG1", "FZ"]  # then markerflow's <marker>_confidence channels
    assert written["parameters"]["ANALOG"]["RATE"]["value"][0] == 200.0
    np.testing.assert_allclose(written["data"]["analogs"][:, :2], given["data"]["analogs"], atol=1e-6)

    point_labels = [str(label).strip() for label in written["parameters"]["POINT"]["LABELS"]["value"]]
    assert point_labels[:own] == [*names, "EXTRA"] and all(label.startswith("*") for label in point_labels[own:])
    out_points, in_points = written["data"]["points"][:3, :own], given["data"]["points"][:3]
    np.testing.assert_allclose(out_points[:, -1], in_points[:, -1], atol=1e-6)  # EXTRA untouched
    # and written once: its samples, free in the capture, also came out as an *N trajectory
    stars = written["data"]["points"][:3, own:]
    shown = written["data"]["meta_points"]["residuals"][0, own:] >= 0
    again = np.linalg.norm(stars - in_points[:, -1:], axis=0) < 1e-6
    assert not (again & shown).any()
    residual = written["data"]["meta_points"]["residuals"][0]
    assert (residual[: len(names), :FIT] < 0).all()  # before --start: not labeled
    labeled = residual[: len(names), FIT:] >= 0
    same = np.linalg.norm(out_points[:, : len(names), FIT:] - in_points[:, : len(names), FIT:], axis=0) < 1e-6
    assert same[labeled].all()  # metres in, metres out: each label is the input's own sample, not rescaled
    assert labeled.mean() >= 0.8  # (the first window from the model leaves fast distal markers unlabeled in some frames)


def test_input_lacking_a_model_marker_keeps_numbering_and_unit_and_says_what_is_lost(tmp_path: Path) -> None:
    names, positions, _ = chain(7, frames=FRAMES)
    model = fit_subject(names, positions[:FIT]).model
    source = tmp_path / "take.c3d"
    _input_c3d(source, names[1:], positions[:, 1:] / 1000)  # the lab took S0M0 off
    out, printed = _track(tmp_path, source, model.to_json(), FIT)
    written = ezc3d.c3d(str(out))
    assert written["header"]["points"]["first_frame"] == FIRST + FIT  # the labeled span, numbered as in the input
    assert list(written["parameters"]["POINT"]["UNITS"]["value"]) == ["m"]
    assert "LAB" not in written["parameters"]
    assert "warning: the input has no point for model markers S0M0, so out.c3d is a new C3D of the labels" in printed
    # the input's columns where they were, the model's marker it lacks after them
    assert [str(label).strip() for label in written["parameters"]["POINT"]["LABELS"]["value"]] == [*names[1:], names[0]]
    given = ezc3d.c3d(str(source))["data"]["points"][:3, :, FIT:]
    labeled = written["data"]["meta_points"]["residuals"][0, :-1] >= 0
    assert np.linalg.norm(written["data"]["points"][:3, :-1] - given, axis=0)[labeled].max() < 1e-6


@pytest.mark.skipif(not CMU_85_02.exists(), reason="needs ../shared/data")
def test_real_take_keeps_its_numbering_and_parameters(tmp_path: Path) -> None:
    take = read_labeled(CMU_85_02)
    model = fit_subject(take.names, take.positions[:400]).model
    start, end = 400, 440
    given = ezc3d.c3d(str(CMU_85_02))
    written = ezc3d.c3d(str(_track(tmp_path, CMU_85_02, model.to_json(), start, end)[0]))
    assert written["header"]["points"]["first_frame"] == given["header"]["points"]["first_frame"]
    own = given["data"]["points"].shape[1]  # then the input's samples outside the span, unlabeled (*N)
    assert written["data"]["points"][:, :own].shape == given["data"]["points"].shape
    for group in ("TRIAL", "SUBJECTS", "EVENT_CONTEXT", "FORCE_PLATFORM"):
        assert written["parameters"][group].keys() == given["parameters"][group].keys()
    assert written["parameters"]["POINT"]["UNITS"]["value"] == given["parameters"]["POINT"]["UNITS"]["value"]
    labeled = written["data"]["meta_points"]["residuals"][0, :own, start:end] >= 0
    points = written["data"]["points"][:3, :own, start:end]
    same = np.linalg.norm(points - given["data"]["points"][:3, :, start:end], axis=0) < 1e-3
    assert labeled.mean() >= 0.8 and same[labeled].all()
    assert (written["data"]["meta_points"]["residuals"][0, :own, :start] < 0).all()


def _track_extra(tmp_path: Path, out: Path) -> tuple[list[str], np.ndarray, dict]:
    """A model of 7 markers, a C3D take in metres with one more (``EXTRA``), tracked from frame
    FIT into ``out`` with ``--json``: the model's names, the input's mm positions, the summary."""
    names, positions, _ = chain(7, frames=FRAMES)
    subject, source = tmp_path / "subject.json", tmp_path / "take.c3d"
    subject.write_text(fit_subject(names, positions[:FIT]).model.to_json())
    extra = positions[:, :1] + np.array([0.0, 0.0, 150.0])
    taken = np.concatenate([positions, extra], axis=1)
    _input_c3d(source, [*names, "EXTRA"], taken / 1000)
    result = CliRunner().invoke(app, ["-q", "track", str(source), "--model", str(subject), "--start", str(FIT),
                                      "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    return names, taken, json.loads(result.stdout)


@pytest.mark.parametrize("suffix", [".trc", ".csv"])
def test_a_table_from_a_model_keeps_the_inputs_markers_the_model_lacks(tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"out{suffix}"
    names, taken, _ = _track_extra(tmp_path, out)
    written = read_labeled(out)
    assert written.names[: len(names)] == names and "EXTRA" in written.names
    np.testing.assert_allclose(written.positions[:, written.names.index("EXTRA")], taken[FIT:, -1], atol=1e-3)


def test_the_leftover_count_is_of_what_the_c3d_copy_holds(tmp_path: Path) -> None:
    """EXTRA's samples are free in the capture; the copy keeps them as EXTRA, not again as *N,
    and the summary counts only the *N samples the file holds."""
    out = tmp_path / "out.c3d"
    _, _, summary = _track_extra(tmp_path, out)
    written = ezc3d.c3d(str(out))
    labels = [str(label).strip() for label in written["parameters"]["POINT"]["LABELS"]["value"]]
    stars = [i for i, label in enumerate(labels) if label.startswith("*")]
    held = int((written["data"]["meta_points"]["residuals"][0, stars, FIT:] >= 0).sum())
    assert summary["unlabeled_points"] == held


def test_a_model_marker_never_takes_a_carried_markers_point(tmp_path: Path) -> None:
    """EXTRA rides 6 mm from S1M1 while S1M1 is unseen for 40 frames: EXTRA keeps the input's
    name, so a model marker on its point wrote one point under two names."""
    names, positions, _ = chain(7, frames=FRAMES)
    subject, source, out = tmp_path / "subject.json", tmp_path / "take.c3d", tmp_path / "out.csv"
    subject.write_text(fit_subject(names, positions[:FIT]).model.to_json())
    near = names.index("S1M1")
    extra = positions[:, near : near + 1] + np.array([0.0, 6.0, 0.0])
    taken = np.concatenate([positions, extra], axis=1)
    taken[FIT + 5 : FIT + 45, near] = np.nan
    _input_c3d(source, [*names, "EXTRA"], taken / 1000)
    result = CliRunner().invoke(app, ["-q", "track", str(source), "--model", str(subject), "--start", str(FIT),
                                      "--out", str(out)])
    assert result.exit_code == 0, result.output
    written = read_labeled(out)
    model_markers = written.positions[:, : len(names)]
    on_extra = np.linalg.norm(model_markers - taken[FIT:, None, -1], axis=2) < 1e-3
    assert not on_extra.any(), f"model markers on EXTRA's point in {int(on_extra.sum())} marker-frames"


def test_a_model_of_another_subject_is_named_as_a_cause_of_doubt(tmp_path: Path) -> None:
    """Same marker names, other placements: the labels are mostly doubtful, and the line says
    the model may be someone else's; the subject's own model gives no such line."""
    printed = {}
    for fitted in (8, 9):
        names, positions, _ = chain(fitted, frames=FRAMES)
        take_names, take, _ = chain(8, frames=FRAMES)
        assert names == take_names
        source = tmp_path / "take.c3d"
        _input_c3d(source, names, take / 1000)
        printed[fitted] = _track(tmp_path, source, fit_subject(names, positions[:FIT]).model.to_json(), 0)[1]
    assert "that the model is of this subject" not in printed[8]
    assert "that the model is of this subject and marker set" in printed[9]


def test_a_table_from_a_model_keeps_the_inputs_column_order(tmp_path: Path) -> None:
    """track --model wrote the model's order, the service the input's: two files for one take."""
    names, positions, _ = chain(7, frames=FRAMES)
    subject, source, out = tmp_path / "subject.json", tmp_path / "take.c3d", tmp_path / "out.csv"
    subject.write_text(fit_subject(names, positions[:FIT]).model.to_json())
    _input_c3d(source, names[::-1], positions[:, ::-1] / 1000)
    result = CliRunner().invoke(app, ["-q", "track", str(source), "--model", str(subject), "--start", str(FIT),
                                      "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert read_labeled(out).names == names[::-1]
