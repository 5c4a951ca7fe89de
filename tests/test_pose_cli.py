"""``markerflow pose`` end to end on a small synthetic take, and its one-line errors on bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import cv2
import numpy as np
import pytest
from pose_scenes import background, keypoints, walking
from typer.testing import CliRunner

from formulations.pose.human import human_model
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.render import render_silhouette
from service.cli.app import app
from service.io.calibration import load_calibration
from service.io.formats.trc import read_trc
from service.pose.openpose import write_openpose_file

REPO = Path(__file__).resolve().parents[1]
CALIBRATION = pytest.importorskip("conftest").DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"
pytestmark = pytest.mark.skipif(not CALIBRATION.exists(), reason="Pose2Sim demo calibration not present")
FRAMES = 4


def run_cli(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``markerflow -q pose ARGS`` as a user runs it, in a process of its own."""
    command = [sys.executable, "-m", "service.cli", "-q", "pose", *map(str, args)]
    return subprocess.run(command, cwd=REPO, env={**os.environ, "COLUMNS": "50"}, capture_output=True, text=True, timeout=120)


def run_inline(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """The same in this process (the bad-input cases: no process start-up per case)."""
    result = CliRunner(env={"COLUMNS": "50"}).invoke(app, ["-q", "pose", *map(str, args)])
    return subprocess.CompletedProcess(args, result.exit_code, result.stdout, result.stderr)


def write_take(folder: Path, blank_frame: int | None = None) -> Path:
    """Four cameras x FRAMES frames of a walking body's keypoints in Pose2Sim's layout; nobody in ``blank_frame``."""
    model = human_model()
    detections = keypoints(model, walking(model, FRAMES), load_calibration(CALIBRATION), 1.0, np.random.default_rng(0))
    for c in range(detections.shape[1]):
        camera = folder / f"cam{c + 1:02d}_json"
        camera.mkdir(parents=True)
        for f in range(FRAMES):
            people = detections[f, c][None] if f != blank_frame else np.empty((0, 25, 3))
            write_openpose_file(camera / f"cam{c + 1:02d}.{f:04d}.json", people)
    return folder


def test_a_take_is_fitted_and_written_in_the_calibrations_units_with_a_person_missing_for_a_frame(tmp_path) -> None:
    take = write_take(tmp_path / "take", blank_frame=2)
    result = run_cli(take, "--calibration", CALIBRATION, "--out", tmp_path / "pose.trc", "--particles", "100", "--layers", "4")
    assert result.returncode == 0, result.stderr
    assert "1 without data" in result.stdout
    trc = read_trc(tmp_path / "pose.trc")
    assert trc.source is not None and trc.source.unit == "m" and trc.n_frames == FRAMES
    assert {"RHip", "RKnee", "RAnkle", "Neck"} <= set(trc.names) and "RClavicle" not in trc.names
    assert np.isfinite(trc.positions).all()
    assert (tmp_path / "pose.png").read_bytes()[:4] == b"\x89PNG"


def test_no_refine_writes_the_particle_filters_own_fit(tmp_path) -> None:
    """--no-refine reaches the fit: the APF alone is written, and it differs from the polished fit."""
    take = write_take(tmp_path / "take")
    fits = {}
    for flag in ("--refine", "--no-refine"):
        out = tmp_path / f"pose{flag}.trc"
        result = run_inline(take, "--calibration", CALIBRATION, "--out", out, "--particles", "60", "--layers", "3", flag)
        assert result.returncode == 0, result.stderr
        fits[flag] = read_trc(out).positions
    assert fits["--refine"].shape == fits["--no-refine"].shape
    assert np.abs(fits["--refine"] - fits["--no-refine"]).max() > 1e-3


def one_line_error(result: subprocess.CompletedProcess[str], *words: str) -> None:
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    for word in words:
        assert word in lines[0]


def test_a_camera_missing_from_the_calibration_is_one_line(tmp_path) -> None:
    take = write_take(tmp_path / "take")
    tables = tomllib.loads(CALIBRATION.read_text())
    three = [f"[{name}]\n" + "".join(f"{key} = {json.dumps(value)}\n" for key, value in table.items())
             for name, table in tables.items() if name not in ("cam_04", "metadata")]
    (tmp_path / "three.toml").write_text("\n".join(three))
    one_line_error(run_inline(take, "--calibration", tmp_path / "three.toml", "--out", tmp_path / "p.trc"), "cam04_json")


def test_a_camera_without_a_file_for_a_frame_is_fitted_without_it_there_and_said(tmp_path) -> None:
    """Refused as "different frame counts" when the files were paired by their order; joined on
    the frame number, the other cameras still see frame 3 (``test_pose_frame_numbers``)."""
    take = write_take(tmp_path / "take")
    (take / "cam03_json" / "cam03.0003.json").unlink()
    result = run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", "--particles", "20", "--layers", "2")
    assert result.returncode == 0, result.stderr
    assert "cam03_json has no file for 1 (3): fitted without that camera there" in result.stderr
    assert np.isfinite(read_trc(tmp_path / "p.trc").positions).all()


def test_a_json_that_is_not_openpose_is_one_line(tmp_path) -> None:
    take = write_take(tmp_path / "take")
    (take / "cam02_json" / "cam02.0001.json").write_text('{"frames": []}')
    one_line_error(run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc"), "cam02.0001.json", "OpenPose")
    (take / "cam02_json" / "cam02.0001.json").write_text('{"people": [{"pose_keypoints_2d": [1, 2, 3]}]}')
    one_line_error(run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc"), "BODY_25B has 75")


def test_a_folder_without_camera_folders_and_a_wrong_suffix_are_one_line(tmp_path) -> None:
    one_line_error(run_inline(tmp_path, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc"), "camNN_json")
    one_line_error(run_inline(tmp_path, "--calibration", CALIBRATION, "--out", tmp_path / "p.c3d"), ".trc")


def test_per_camera_image_folders_are_fitted_by_edges_and_foreground(tmp_path) -> None:
    """Rendered silhouettes (real video of the demo is not available): the body is found near the truth."""
    cameras = load_calibration(CALIBRATION)
    model = human_model()
    X = walking(model, 1)
    rng = np.random.default_rng(0)
    for c, camera in enumerate(cameras):
        folder = tmp_path / "take" / f"cam{c + 1:02d}"
        folder.mkdir(parents=True)
        back = background(camera, rng)
        cv2.imwrite(str(folder / "background.png"), back)
        for f in range(len(X)):
            image = render_silhouette(model, X[f], camera, back)
            cv2.imwrite(str(folder / f"{f:04d}.png"), np.clip(image + rng.normal(0, 4, image.shape), 0, 255).astype(np.uint8))
    result = run_cli(tmp_path / "take", "--calibration", CALIBRATION, "--out", tmp_path / "pose.trc",
                     "--particles", "100", "--layers", "4")
    assert result.returncode == 0, result.stderr
    trc = read_trc(tmp_path / "pose.trc")
    truth = forward_kinematics(model, X).positions[:, [model.index(n) for n in trc.names]] * 1000.0
    trunk = [trc.names.index("CHip"), trc.names.index("Neck")]  # limbs need the bench's budget, 600 x 15
    assert (np.linalg.norm(trc.positions[:, trunk] - truth[:, trunk], axis=2) < 100.0).all()


def test_a_subject_model_without_keypoint_names_is_one_line_for_keypoint_input(tmp_path) -> None:
    from test_pose_markers import leg

    take = write_take(tmp_path / "take")
    (tmp_path / "subject.json").write_text(leg().to_json())
    result = run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", "--model", tmp_path / "subject.json")
    one_line_error(result, "no joint of the model is named like a keypoint")
    (tmp_path / "subject.json").write_text("{}")
    result = run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", "--model", tmp_path / "subject.json")
    one_line_error(result, "subject.json", "version")


@pytest.mark.parametrize(("option", "value", "said"), [
    ("--seed", "-1", "--seed must be >= 0"),  # was numpy's ValueError as a traceback
    ("--particles", "100000000", "2 to 100,000 particles"),  # was a MemoryError of 24.6 GiB
    ("--rate", "inf", "--rate must be a finite number > 0"),  # was a TRC with DataRate inf, every time 0
])
def test_out_of_range_options_are_one_line(tmp_path, option: str, value: str, said: str) -> None:
    take = write_take(tmp_path / "take")
    one_line_error(run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", option, value), said)


def _leg_naming_rknee() -> dict:
    """The leg model of ``test_pose_markers`` as JSON, its first joint named RKnee (a keypoint)."""
    from test_pose_markers import leg

    data: dict = json.loads(leg().to_json())
    old = data["joints"][0]["name"]
    data["joints"][0]["name"] = "RKnee"
    for limb in data["limbs"]:
        limb["joints"] = ["RKnee" if name == old else name for name in limb["joints"]]
    return data


def _pose_with(tmp_path, data: dict) -> subprocess.CompletedProcess[str]:
    """``pose`` of a small take with the model ``data``, a quick schedule."""
    take = write_take(tmp_path / "take")
    (tmp_path / "subject.json").write_text(json.dumps(data))
    result = run_inline(take, "--calibration", CALIBRATION, "--out", tmp_path / "p.trc", "--model", tmp_path / "subject.json",
                        "--particles", "20", "--layers", "2")
    assert result.returncode == 0, result.stderr
    return result


def test_a_subject_model_naming_few_keypoints_is_warned_of(tmp_path) -> None:
    """A model naming one keypoint was fitted to it alone and reported a small error."""
    result = _pose_with(tmp_path, _leg_naming_rknee())
    assert "warning: the model names 1 of the 21 keypoints detected (RKnee)" in result.stderr


def test_joints_off_the_bodys_tree_are_named(tmp_path) -> None:
    """A model whose segments form two trees: the smaller one's joint was left out of the TRC without a word."""
    data = _leg_naming_rknee()
    data["segments"] += [{**segment, "name": f"far{k}", "markers": [f"far{k}_{m}" for m in segment["markers"]]}
                         for k, segment in enumerate(data["segments"][:2])]
    data["joints"].append({**data["joints"][0], "name": "LAnkle", "segments": ["far0", "far1"]})
    result = _pose_with(tmp_path, data)
    assert "1 joint on segments not joined to the rest of the body, not fitted or written: LAnkle" in result.stderr


def test_image_folders_are_ordered_and_paired_by_the_numbers_in_their_names(tmp_path) -> None:
    """Sorted names put f10.png before f9.png, and cameras were paired by position."""
    from service.errors import InputError
    from service.pose.images import image_folders

    for camera, numbers in (("cam1", (8, 9, 10)), ("cam2", (8, 9, 10))):
        (tmp_path / camera).mkdir()
        for n in numbers:
            cv2.imwrite(str(tmp_path / camera / f"f{n}.png"), np.zeros((4, 4), np.uint8))
    numbers, folders = image_folders(tmp_path)
    assert numbers == [8, 9, 10]
    assert {name: [f.name for f in files] for name, files in folders.items()} == {
        "cam1": ["f8.png", "f9.png", "f10.png"], "cam2": ["f8.png", "f9.png", "f10.png"]}
    (tmp_path / "cam2" / "f8.png").rename(tmp_path / "cam2" / "f11.png")
    with pytest.raises(InputError, match=r"the cameras' images are numbered differently: cam1 8-10 \(3\), cam2 9-11 \(3\)"):
        image_folders(tmp_path)
