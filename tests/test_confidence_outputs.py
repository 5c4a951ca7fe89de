"""Every label's confidence reaches every output: C3D (analog channels), CSV, the result
JSON, stored windows (and a resumed run), and ``eval --json``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import ezc3d
import numpy as np

from service.evaluation.scenario import Scenario
from service.evaluation.simulate_cloud import simulate_cloud
from service.io.formats import read_labeled, write_labeled
from service.io.formats.csv import read_csv_labeled
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.outcome import WindowOutcome
from service.labeling.stats import doubtful_labels
from service.server.results import trajectories_from_bytes, trajectories_json, trajectories_to_bytes

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
CMU = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
VICON = DATA / "c3d_ezc3d_testfiles" / "Vicon.c3d"


def _labels(names: list[str], frames: int, seed: int) -> LabeledTrajectories:
    rng = np.random.default_rng(seed)
    positions = rng.uniform(-500, 500, size=(frames, len(names), 3))
    positions[3, 0] = np.nan
    return LabeledTrajectories(names, positions, np.isnan(positions).any(axis=2), 100.0,
                               confidence=rng.uniform(size=(frames, len(names))))


def _analog_confidence(path: Path, names: list[str]) -> np.ndarray:
    """``(frames, markers)`` the ``<name>_confidence`` channels as ezc3d reads them, one sample per frame."""
    c3d = ezc3d.c3d(str(path))
    labels = [str(label).strip() for label in c3d["parameters"]["ANALOG"]["LABELS"]["value"]]
    analogs = c3d["data"]["analogs"][0]
    ratio = analogs.shape[1] // c3d["data"]["points"].shape[2]
    samples = analogs[[labels.index(f"{name}_confidence") for name in names]]
    assert np.array_equal(samples, np.repeat(samples[:, ::ratio], ratio, axis=1))  # constant within a frame
    return samples[:, ::ratio].T


def test_c3d_holds_confidence_as_analog_channels_alone_and_beside_a_files_analogs(tmp_path: Path) -> None:
    alone = _labels(["A", "B", "C"], 30, 0)
    write_labeled(tmp_path / "alone.c3d", alone)
    assert np.allclose(_analog_confidence(tmp_path / "alone.c3d", alone.names), alone.confidence, atol=1e-6)
    source = read_labeled(VICON)
    before = ezc3d.c3d(str(VICON))["data"]["analogs"]
    labels = _labels(source.names[:4], 50, 1)
    write_labeled(tmp_path / "vicon.c3d", labels, source.source, start=10)
    got = _analog_confidence(tmp_path / "vicon.c3d", labels.names)
    assert np.allclose(got[10:60], labels.confidence, atol=1e-6) and (got[:10] == 0).all() and (got[60:] == 0).all()
    after = ezc3d.c3d(str(tmp_path / "vicon.c3d"))["data"]["analogs"]
    assert np.allclose(after[:, : before.shape[1]], before)  # the force plates and EMG are untouched
    relabeled = read_labeled(tmp_path / "vicon.c3d")  # a relabel replaces its channels rather than adding more
    write_labeled(tmp_path / "again.c3d", labels, relabeled.source, start=10)
    assert ezc3d.c3d(str(tmp_path / "again.c3d"))["data"]["analogs"].shape == after.shape


def test_csv_and_result_json_round_trip_confidence(tmp_path: Path) -> None:
    labels = _labels(["A", "B"], 12, 2)
    labels.confidence[5, 1] = np.nan  # a frame no window labeled
    write_labeled(tmp_path / "x.csv", labels)
    assert np.allclose(read_csv_labeled(tmp_path / "x.csv").confidence, labels.confidence, equal_nan=True)
    document = json.loads(json.dumps(trajectories_json(labels)))
    assert document["confidence"][5][1] is None
    assert np.allclose(np.array(document["confidence"], dtype=float), labels.confidence, equal_nan=True)
    assert np.array_equal(trajectories_from_bytes(trajectories_to_bytes(labels)).confidence, labels.confidence,
                          equal_nan=True)


def test_stored_windows_keep_confidence_and_a_resumed_run_carries_it_alike() -> None:
    simulated = simulate_cloud(read_labeled(CMU), Scenario(noise_mm=2.0, drop_rate=0.2, ghosts_per_frame=5.0, frames=100))
    labeling = CaptureLabeling(simulated.capture())
    outcomes = list(labeling.windows())
    stored = [WindowOutcome.from_bytes(o.to_bytes()) for o in outcomes]
    resumed = stored[:2] + list(labeling.windows(after=stored[1]))
    for kept, made in zip(stored, outcomes):  # the trusted shapes a resumed run is carried on from
        assert kept.trusted_mean is not None and kept.trusted_var is not None
        assert np.array_equal(kept.trusted_mean, made.trusted_mean) and np.array_equal(kept.trusted_var, made.trusted_var)
    whole = labeling.result(outcomes).confidence
    assert np.isfinite(whole).all() and (whole[0] == 1).all() and whole.min() < 1
    assert np.array_equal(labeling.result(resumed).confidence, whole)
    for o in outcomes:  # each window's statistics count its own doubtful labels
        assert o.stats.doubtful == doubtful_labels(o.confidence, o.point_index < 0).sum()
        assert o.stats.labels == (o.point_index >= 0).sum()


def test_eval_json_reports_doubtful_share_and_recall(tmp_path: Path) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text('mode = "cloud"\nnoise_mm = 2.0\ndrop_rate = 0.2\nghosts_per_frame = 5.0\nframes = 80\n')
    run = subprocess.run([sys.executable, "-m", "service.cli", "-q", "eval", str(CMU), "--scenario", str(scenario),
                          "--json"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert 0.0 <= summary["doubtful_share"] <= 1.0
    assert summary["doubtful_recall"] is None or 0.0 <= summary["doubtful_recall"] <= 1.0
