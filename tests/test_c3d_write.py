"""C3D output past what ezc3d's writer does alone: any spelling of the suffix, and more
than 255 analog channels (the label confidences of as many markers)."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest

from service.io.formats import read_labeled, write_labeled
from service.io.formats.c3d import read_c3d, write_c3d
from service.io.recording import LabeledTrajectories
from tests.test_formats import _assert_matches, _occluded_cmu


@pytest.mark.parametrize("name", ["OUT.C3D", "out.C3d"])
def test_c3d_named_in_capitals_is_written_at_that_name(name: str, tmp_path: Path) -> None:
    """ezc3d appends ``.c3d`` to any other ending: the file asked for was left empty."""
    traj = _occluded_cmu(frames=20)
    (tmp_path / name).write_bytes(b"an older file")
    write_labeled(tmp_path / name, traj)
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]
    _assert_matches(read_c3d(tmp_path / name).positions, traj, atol=1e-3)


def test_c3d_of_more_than_255_markers_reads_back(tmp_path: Path) -> None:
    """Each marker's confidence channel past the 255th goes on in ANALOG:LABELS2, SCALE2, ...:
    a parameter of more than 255 values is no C3D any reader takes."""
    base = _occluded_cmu(frames=5)
    copies = 7  # 287 markers
    names = [f"S{k}:{name}" for k in range(copies) for name in base.names]
    positions = np.concatenate([base.positions + [3000.0 * k, 0, 0] for k in range(copies)], axis=1)
    occluded = np.concatenate([base.occluded] * copies, axis=1)
    confidence = np.linspace(0.1, 1.0, positions.shape[0] * len(names)).reshape(positions.shape[0], len(names))
    traj = LabeledTrajectories(names, positions, occluded, base.rate, confidence=confidence)
    out = tmp_path / "many.c3d"
    write_c3d(out, traj)
    raw = ezc3d.c3d(str(out))
    analog = raw["parameters"]["ANALOG"]
    labels = list(analog["LABELS"]["value"]) + list(analog["LABELS2"]["value"])
    assert labels == [f"{name}_confidence" for name in names]
    for key in ("SCALE", "UNITS", "DESCRIPTIONS"):
        assert len(analog[key]["value"]) == 255 and len(analog[f"{key}2"]["value"]) == len(names) - 255
    assert list(analog["UNITS2"]["value"]) == ["1"] * (len(names) - 255)
    np.testing.assert_allclose(raw["data"]["analogs"][0, :, :], confidence.T, atol=1e-6)
    rec = read_c3d(out)
    assert rec.names == names
    _assert_matches(rec.positions, traj, atol=1e-3)


def test_past_255_channels_the_inputs_own_analog_channels_keep_their_parameters(tmp_path: Path) -> None:
    """250 markers and 10 EMG channels: the channels' units, scales and descriptions stay
    theirs when the 250 confidence channels push the count past 255."""
    markers, frames, emg = 250, 6, 10
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = [f"M{i}" for i in range(markers)]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    points = np.ones((4, markers, frames))
    points[:3] = np.random.default_rng(0).normal(0.0, 500.0, (3, markers, frames))
    c3d["data"]["points"] = points
    analog = c3d["parameters"]["ANALOG"]
    analog["LABELS"]["value"] = [f"EMG{i}" for i in range(emg)]
    analog["UNITS"]["value"] = ["V"] * emg
    analog["DESCRIPTIONS"]["value"] = [f"emg {i}" for i in range(emg)]
    analog["SCALE"]["value"] = np.full(emg, 0.5)
    analog["RATE"]["value"] = np.array([1000.0])
    samples = np.arange(emg * frames * 10, dtype=float).reshape((1, emg, frames * 10))
    c3d["data"]["analogs"] = samples
    c3d.write(str(tmp_path / "in.c3d"))
    rec = read_labeled(tmp_path / "in.c3d")
    labels = LabeledTrajectories(rec.names, rec.positions, np.zeros((frames, markers), bool), rec.rate,
                                 confidence=np.full((frames, markers), 0.7))
    write_labeled(tmp_path / "out.c3d", labels, rec.source)
    out = ezc3d.c3d(str(tmp_path / "out.c3d"))
    written = out["parameters"]["ANALOG"]
    assert list(written["UNITS"]["value"][: emg + 1]) == ["V"] * emg + ["1"]
    assert list(written["DESCRIPTIONS"]["value"][:emg]) == [f"emg {i}" for i in range(emg)]
    np.testing.assert_allclose(written["SCALE"]["value"][: emg + 1], [0.5] * emg + [1.0])
    assert written["LABELS2"]["value"][-1] == f"M{markers - 1}_confidence"
    np.testing.assert_allclose(out["data"]["analogs"][0, :emg], samples[0], atol=1e-4)
    np.testing.assert_allclose(out["data"]["analogs"][0, emg:], 0.7, atol=1e-6)


def test_a_c3d_output_shares_the_inputs_analog_samples_and_leaves_the_input_as_read(tmp_path: Path) -> None:
    """The copy written into shares the input's analog array (``c3d_copy.writable``: it is most
    of a file with EMG or force plates) and changes nothing of the input: written twice, the
    same file, and the input's points, residuals, analogs and labels as read."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ["A", "B", "C"]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    points = np.ones((4, 3, 8))
    points[:3] = np.random.default_rng(1).normal(0.0, 500.0, (3, 3, 8))
    c3d["data"]["points"] = points
    c3d["parameters"]["ANALOG"]["LABELS"]["value"] = ["EMG"]
    c3d["parameters"]["ANALOG"]["RATE"]["value"] = np.array([1000.0])
    c3d["data"]["analogs"] = np.arange(80, dtype=float).reshape((1, 1, 80))
    c3d.write(str(tmp_path / "in.c3d"))
    rec = read_labeled(tmp_path / "in.c3d")
    source = rec.source.c3d
    before = {key: np.copy(source["data"][key]) for key in ("points", "analogs")}
    residuals = np.copy(source["data"]["meta_points"]["residuals"])
    labels = list(source["parameters"]["POINT"]["LABELS"]["value"])
    occluded = np.zeros((8, 3), bool)
    occluded[2:4, 1] = True
    traj = LabeledTrajectories(rec.names, rec.positions, occluded, rec.rate, confidence=np.full((8, 3), 0.9),
                               unlabeled=np.where(occluded[..., None], rec.positions, np.nan))
    write_labeled(tmp_path / "one.c3d", traj, rec.source)
    write_labeled(tmp_path / "two.c3d", traj, rec.source)
    assert (tmp_path / "one.c3d").read_bytes() == (tmp_path / "two.c3d").read_bytes()
    for key, value in before.items():
        np.testing.assert_array_equal(source["data"][key], value)
    np.testing.assert_array_equal(source["data"]["meta_points"]["residuals"], residuals)
    assert list(source["parameters"]["POINT"]["LABELS"]["value"]) == labels
    np.testing.assert_allclose(ezc3d.c3d(str(tmp_path / "one.c3d"))["data"]["analogs"][0, 0], np.arange(80), atol=1e-4)
