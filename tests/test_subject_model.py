"""The subject model (Ringer & Lasenby 2004): grouping, joints, limb lengths, JSON and ``markerflow model``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from formulations.errors import FormulationError
from formulations.subject.fit import fit_subject
from formulations.subject.model import SubjectModel
from service.cli.app import app
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, SourceFile

CMU_85_02 = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
LIMB = 400.0  # mm between the joints of a synthetic segment


def chain(seed: int, segments: int = 4, markers: int = 4, frames: int = 300, motion: float = 0.6):
    """Names, ``(frames, markers, 3)`` positions with 1 mm noise, and the true joint centres.

    Segment s hangs from joint s-1 at its origin; joint s is at (0, 0, -LIMB) in segment s.
    Every joint turns about all three axes by up to about ``motion`` rad.
    """
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, frames)[:, None]

    def turning() -> np.ndarray:
        freq, phase = rng.uniform(1.5, 6.0, (2, 3)), rng.uniform(0, 2 * np.pi, (2, 3))
        angles = motion * (np.sin(2 * np.pi * freq[0] * t + phase[0]) + 0.5 * np.sin(2 * np.pi * freq[1] * t + phase[1]))
        return Rotation.from_rotvec(angles).as_matrix()

    rotation = turning()
    origin = np.hstack([200 * np.sin(2 * np.pi * t), 100 * np.cos(2 * np.pi * t), 1000 + 50 * t])
    names, columns, centres = [], [], []
    for s in range(segments):
        local = rng.normal(0, 60, (markers, 3))
        local[:, :2] += 40 * np.sign(local[:, :2])  # off the long axis, as on skin
        local[:, 2] = rng.uniform(-350, -50, markers)
        for m, point in enumerate(local):
            names.append(f"S{s}M{m}")
            columns.append(np.einsum("kij,j->ki", rotation, point) + origin)
        if s < segments - 1:
            origin = np.einsum("kij,j->ki", rotation, np.array([0.0, 0.0, -LIMB])) + origin
            centres.append(origin)
            rotation = np.einsum("kij,kjl->kil", rotation, turning())
    positions = np.stack(columns, axis=1) + rng.normal(0, 1.0, (frames, len(names), 3))
    return names, positions, centres


@pytest.mark.parametrize("seed", range(4))
def test_synthetic_chain_groups_joints_and_limbs(seed: int) -> None:
    names, positions, centres = chain(seed)
    positions[np.random.default_rng(seed).random(positions.shape[:2]) < 0.05] = np.nan  # gaps are allowed
    fit = fit_subject(names, positions)
    assert [s.markers for s in fit.model.segments] == [[f"S{s}M{m}" for m in range(4)] for s in range(4)]
    assert not fit.model.singles
    assert len(fit.model.joints) == 3
    for joint in fit.model.joints:
        first = min(int(name[1]) for name in joint.segments)  # joint s links segments s and s+1
        assert sorted(int(name[1]) for name in joint.segments) == [first, first + 1]
        error = np.linalg.norm(fit.centres[joint.name] - centres[first], axis=1)
        assert np.nanmedian(error) < 3.0, joint.name
    assert len(fit.model.limbs) == 2
    for limb in fit.model.limbs:
        assert abs(limb.length - LIMB) < 3.0


def test_a_limb_whose_joints_are_never_posed_together_is_measured_on_its_segment() -> None:
    """Segment 0 seen only in the first half, segment 2 only in the second: the two joints of
    segment 1 never exist in one frame. Their mean distance over frames is undefined; the
    length is the centres' distance in segment 1's own frame, and the model reads back
    (an infinite length made the fitted model of 03_rolling unreadable)."""
    names, positions, _ = chain(3)
    half = len(positions) // 2
    positions[half:, :4] = np.nan
    positions[:half, 8:12] = np.nan
    model = fit_subject(names, positions).model
    middle = [limb for limb in model.limbs if limb.segment == "S1M0"]
    assert len(middle) == 1 and abs(middle[0].length - LIMB) < 3.0
    assert SubjectModel.from_json(model.to_json()) == model


def test_a_marker_alone_on_its_segment_is_kept_as_a_single() -> None:
    names, positions, _ = chain(0)
    keep = [i for i, name in enumerate(names) if not name.startswith("S3") or name == "S3M0"]
    fit = fit_subject([names[i] for i in keep], positions[:, keep])
    assert [s.marker for s in fit.model.singles] == ["S3M0"]
    assert fit.model.singles[0].segments[0] == "S2M0"  # the segment it hangs from is the nearest
    assert len(fit.model.segments) == 3


def test_static_take_fails_naming_the_markers() -> None:
    names, positions, _ = chain(1, motion=0.0)
    with pytest.raises(FormulationError, match="too static to separate segments: markers S0M0, S0M1"):
        fit_subject(names, positions)


def test_static_body_beside_one_moving_part_fails() -> None:
    """A static trial whose head nods: the head is a segment of its own, the rest one rigid
    body; jointing the two would be a model of nothing (the head's centre is anywhere)."""
    names, positions, _ = chain(1, motion=0.0)
    t = np.linspace(0, 1, len(positions))[:, None]
    nod = Rotation.from_rotvec(0.4 * np.sin(2 * np.pi * 3 * t) * np.array([1.0, 0.3, 0.0])).as_matrix()
    head = np.array([[60.0, 0, 0], [-60, 0, 0], [0, 80, 40]])
    top = positions[:, 0] + np.array([0.0, 0.0, 300.0])
    moving = np.einsum("kij,pj->kpi", nod, head) + top[:, None]
    positions = np.concatenate([positions, moving], axis=1)
    with pytest.raises(FormulationError, match="too static to separate segments: markers S0M0, S0M1"):
        fit_subject([*names, "H0", "H1", "H2"], positions)


def test_too_few_frames_fails() -> None:
    names, positions, _ = chain(1, frames=10)
    with pytest.raises(FormulationError, match="only 10 frames"):
        fit_subject(names, positions)


def test_json_round_trip_and_wrong_version_refused() -> None:
    names, positions, _ = chain(2)
    model = fit_subject(names, positions).model
    text = model.to_json()
    assert SubjectModel.from_json(text) == model
    data = json.loads(text)
    data["version"] = 99
    with pytest.raises(FormulationError, match="version 99 is not supported"):
        SubjectModel.from_json(json.dumps(data))
    with pytest.raises(FormulationError, match="not JSON"):
        SubjectModel.from_json(text[:50])
    del data["segments"][0]["spread"]
    data["version"] = 1
    with pytest.raises(FormulationError, match="malformed"):
        SubjectModel.from_json(json.dumps(data))
    del data["joints"]  # said "malformed: KeyError 'joints'", a Python exception's name
    with pytest.raises(FormulationError, match="malformed: it has no 'joints' \\(a model holds segments"):
        SubjectModel.from_json(json.dumps(data))


def _segment_of(fit: dict, marker: str) -> str | None:
    return next((s["name"] for s in fit["segments"] if marker in s["markers"]), None)


@pytest.mark.skipif(not CMU_85_02.exists(), reason="needs ../shared/data")
def test_cli_fits_cmu_85_02(tmp_path: Path) -> None:
    take = read_labeled(CMU_85_02)
    head = take.positions[:400]
    trc = tmp_path / "85_02_head.trc"
    write_labeled(trc, LabeledTrajectories(take.names, head, np.isnan(head).any(axis=2), take.rate))
    out, centres = tmp_path / "subject.json", tmp_path / "centres.trc"
    result = CliRunner().invoke(app, ["model", str(trc), "--out", str(out), "--centres", str(centres)])
    assert result.exit_code == 0, result.output
    assert "Male:LFHD Male:RFHD Male:LBHD Male:RBHD" in result.output  # the head is one segment
    model = json.loads(out.read_text())
    hand = {_segment_of(model, f"Male:L{m}") for m in ("WRA", "WRB", "FIN", "FRM")}
    assert len(hand - {None}) <= 2
    for side in "LR":
        thigh = {_segment_of(model, f"Male:{side}{m}") for m in ("THI", "KNE")} - {None}
        foot = {_segment_of(model, f"Male:{side}{m}") for m in ("HEE", "MT5", "TOE")} - {None}
        assert foot and not thigh & foot
    joints = read_labeled(centres)
    assert joints.names == [j["name"] for j in model["joints"]] and joints.n_frames == 400
    assert np.isfinite(joints.positions).all()


def test_cli_refuses_a_model_named_other_than_json(tmp_path: Path) -> None:
    """``--out model.c3d`` wrote JSON under a C3D's name."""
    names, positions, _ = chain(3)
    trc = tmp_path / "take.trc"
    write_labeled(trc, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0))
    result = CliRunner().invoke(app, ["model", str(trc), "--out", str(tmp_path / "model.c3d")])
    assert result.exit_code == 2 and "name it .json" in result.output
    assert not (tmp_path / "model.c3d").exists()


def test_cli_refuses_to_pool_takes_of_two_marker_sets(tmp_path: Path) -> None:
    """Two subjects' takes, no name in common, made one model of two bodies side by side."""
    names, positions, _ = chain(3)
    first, second = tmp_path / "a.trc", tmp_path / "b.trc"
    occluded = np.zeros(positions.shape[:2], bool)
    write_labeled(first, LabeledTrajectories(names, positions, occluded, 100.0))
    write_labeled(second, LabeledTrajectories([f"Other:{n}" for n in names], positions, occluded, 100.0))
    result = CliRunner().invoke(app, ["model", str(first), str(second), "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 2 and "b.trc: shares 0 of its" in result.output
    same = CliRunner().invoke(app, ["model", str(first), str(first), "--out", str(tmp_path / "m.json")])
    assert same.exit_code == 0, same.output


def test_cli_static_take_is_one_line_error(tmp_path: Path) -> None:
    names, positions, _ = chain(3, motion=0.0)
    trc = tmp_path / "static.trc"
    write_labeled(trc, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0))
    result = CliRunner().invoke(app, ["model", str(trc), "--out", str(tmp_path / "s.json")])
    assert result.exit_code == 2
    assert "static.trc: too static to separate segments" in result.output
    assert not (tmp_path / "s.json").exists()


def test_cli_learns_from_the_frames_between_start_and_end(tmp_path: Path) -> None:
    """``model --start/--end`` is the model of that stretch written as a take of its own."""
    names, positions, _ = chain(3)
    whole, stretch = tmp_path / "whole.trc", tmp_path / "stretch.trc"
    write_labeled(whole, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0))
    write_labeled(stretch, LabeledTrajectories(names, positions[60:260], np.zeros((200, len(names)), bool), 100.0))
    spans = {"span": ["--start", "60", "--end", "260"], "all": [], "cropped": []}
    for key, span in spans.items():
        source = stretch if key == "cropped" else whole
        result = CliRunner().invoke(app, ["-q", "model", str(source), "--out", str(tmp_path / f"{key}.json"), *span])
        assert result.exit_code == 0, result.output
    read = {key: json.loads((tmp_path / f"{key}.json").read_text()) for key in spans}
    assert read["span"] == read["cropped"] != read["all"]
    refused = CliRunner().invoke(app, ["model", str(whole), "--out", str(tmp_path / "x.json"), "--start", "400"])
    assert refused.exit_code == 2 and "whole.trc: --start 400" in refused.output


def test_cli_writes_joint_centres_in_the_takes_unit(tmp_path: Path) -> None:
    """A take in metres gets its centres in metres, as ``track`` keeps a take's unit (they were mm)."""
    names, positions, centres = chain(3)
    take, out = tmp_path / "take.trc", tmp_path / "centres.trc"
    write_labeled(take, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0),
                  SourceFile(unit="m"))
    result = CliRunner().invoke(app, ["-q", "model", str(take), "--out", str(tmp_path / "m.json"), "--centres", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_text().splitlines()[2].split("\t")[4] == "m"
    written = read_labeled(out)  # read back in mm
    assert np.nanmedian(np.abs(written.positions)) > 100.0  # mm, not metres read as mm


def test_cli_names_the_markers_it_never_saw(tmp_path: Path) -> None:
    names, positions, _ = chain(3)
    positions = positions.copy()
    positions[:, 2] = np.nan  # taken off before the take
    take = tmp_path / "take.trc"
    write_labeled(take, LabeledTrajectories(names, positions, np.isnan(positions).any(axis=2), 100.0))
    result = CliRunner().invoke(app, ["-q", "model", str(take), "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 0, result.output
    assert f"1 marker never seen in the frames learned from, not in the model: {names[2]}" in result.output
    assert names[2] not in (tmp_path / "m.json").read_text()


def test_cli_warns_when_pooled_takes_look_like_two_subjects(tmp_path: Path) -> None:
    """Same names, other placements: pooled, CMU 85_02's subject with 135_02's gave 5 segments
    and every limb marker a single, without a word."""
    printed = {}
    for seed in (3, 4):
        names, positions, _ = chain(seed)
        occluded = np.zeros(positions.shape[:2], bool)
        write_labeled(tmp_path / f"take{seed}.trc", LabeledTrajectories(names, positions, occluded, 100.0))
    first, second = str(tmp_path / "take3.trc"), str(tmp_path / "take4.trc")
    for key, takes in {"two": [first, second], "one": [first, first]}.items():
        result = CliRunner().invoke(app, ["-q", "model", *takes, "--out", str(tmp_path / f"{key}.json")])
        assert result.exit_code == (2 if key == "two" else 0), result.output  # two bodies pooled: nothing rigid left
        printed[key] = result.output
    assert "take4.trc: " in printed["two"] and "another subject, or markers placed again?" in printed["two"]
    assert "another subject" not in printed["one"]


def test_cli_says_when_pooled_takes_differ_only_in_case(tmp_path: Path) -> None:
    """CMU's 85_02 says Male:, 135_02 male:; the refusal gave no hint."""
    names, positions, _ = chain(3)
    occluded = np.zeros(positions.shape[:2], bool)
    write_labeled(tmp_path / "a.trc", LabeledTrajectories(names, positions, occluded, 100.0))
    write_labeled(tmp_path / "b.trc", LabeledTrajectories([n.lower() for n in names], positions, occluded, 100.0))
    result = CliRunner().invoke(app, ["model", str(tmp_path / "a.trc"), str(tmp_path / "b.trc"),
                                      "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 2 and "differ from its names only in upper/lower case" in result.output
