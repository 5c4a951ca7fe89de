"""Doubtful labels (issue 14, item 6): the certificate is about the model's optimum, so the
summary names the labels it vouches for least, and those must be the ones most often wrong."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from service.evaluation.cloud import evaluate
from service.evaluation.scenario import Scenario
from service.io.formats import read_labeled
from service.io.formats.c3d import write_c3d
from service.io.recording import LabeledTrajectories
from service.labeling.stats import (
    DOUBTFUL_WARNING,
    REACQUIRED_FRAMES,
    WindowStats,
    doubtful_fraction,
    doubtful_labels,
    reacquisitions,
)

REPO = Path(__file__).resolve().parents[1]
CMU = REPO.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def _window(template: int, last: int, integral: bool) -> WindowStats:
    return WindowStats(template, last, integral, 0.0 if integral else 0.1, 1.0, 1.0, 0 if integral else 2, "optimal",
                       0.0, 0.0, 0.0, 0.0, 0.0, {})


def test_doubtful_labels_are_reacquisitions_and_fractional_windows() -> None:
    occluded = np.zeros((20, 2), dtype=bool)
    occluded[3:6, 0] = True  # marker 0 hidden in frames 3-5, back in 6
    windows = [_window(0, 9, True), _window(9, 19, False)]
    doubtful = doubtful_labels(occluded, windows)
    expected = np.zeros_like(occluded)
    expected[6 : 6 + REACQUIRED_FRAMES, 0] = True  # occluded in one of the frames before
    expected[10:, :] = True  # the fractional window's frames
    assert np.array_equal(doubtful, expected)
    assert doubtful_fraction(occluded, windows) == expected.sum() / (~occluded).sum()
    assert reacquisitions(["a", "b"], occluded) == {"a": [6]}
    assert doubtful_fraction(np.ones((3, 2), bool), []) == 0.0


def test_doubtful_labels_are_wrong_more_often_than_the_others() -> None:
    """A hard simulated take: the doubtful labels' error rate is several times the others'."""
    scenario = Scenario(noise_mm=2.0, drop_rate=0.2, ghosts_per_frame=5.0, frames=400)
    run = evaluate(read_labeled(CMU), scenario)
    result, capture = run.result, run.capture
    held = np.full(result.point_index.shape, -2)  # the true marker of the point each label took
    for f, taken in enumerate(result.point_index):
        held[f, taken >= 0] = capture.point_marker[f][taken[taken >= 0]]
    labeled = ~result.occluded
    labeled[0] = False  # frame 0 is given
    wrong = labeled & (held != np.arange(held.shape[1]))
    doubtful = doubtful_labels(result.occluded, run.windows) & labeled
    assert wrong.sum() >= 5 and doubtful.sum() >= 100  # errors to find, and doubt that is not everything
    doubtful_rate, other_rate = wrong[doubtful].mean(), wrong[labeled & ~doubtful].mean()
    assert doubtful_rate > 3 * other_rate and doubtful_rate > 0.005
    assert doubtful.sum() < 0.3 * labeled.sum()


def test_track_warns_on_stderr_and_lists_reacquisitions_in_json(tmp_path: Path) -> None:
    rec = read_labeled(CMU)
    occluded = np.zeros((300, rec.n_markers), dtype=bool)
    for m in range(0, rec.n_markers, 2):  # every other marker hidden for 4 frames, every 25 frames
        for f in range(10 + m, 300, 25):
            occluded[f : f + 4, m] = True
    positions = np.where(occluded[..., None], np.nan, rec.positions[:300])
    write_c3d(tmp_path / "gappy.c3d", LabeledTrajectories(rec.names, positions, occluded, rec.rate))
    run = subprocess.run([sys.executable, "-m", "service.cli", "-q", "track", str(tmp_path / "gappy.c3d"), "--out",
                          str(tmp_path / "x.c3d"), "--json"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["certificate"] == "optimal under the model"
    assert summary["doubtful_fraction"] > DOUBTFUL_WARNING
    warning = run.stderr.splitlines()
    assert len(warning) == 1 and warning[0].startswith(f"warning: {summary['doubtful_fraction']:.1%} of the labels")
    assert summary["reacquired"][rec.names[0]][:2] == [14, 39] and rec.names[1] not in summary["reacquired"]
    clean = subprocess.run([sys.executable, "-m", "service.cli", "track", str(CMU), "--out", str(tmp_path / "y.trc")],
                           cwd=REPO, capture_output=True, text=True, timeout=600)
    assert clean.returncode == 0 and "warning" not in clean.stderr, clean.stderr
    assert "windows optimal under the model" in clean.stdout and "0.0% labels doubtful" in clean.stdout
