"""Labels that stop while points keep coming (``service.labeling.lost_subject``): the span,
and ``markerflow track`` saying so when a subject leaves the volume and comes back elsewhere."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from conftest import DATA

from service.io.formats import read_labeled
from service.io.formats.c3d import write_c3d
from service.io.recording import LabeledTrajectories
from service.labeling.lost_subject import MIN_POINTS, away_span, unnamed_span

REPO = Path(__file__).resolve().parents[1]
CMU = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def test_the_span_is_the_unlabeled_run_with_the_most_frames_that_hold_a_constellation() -> None:
    occluded = np.zeros((40, 2), bool)
    occluded[5:12] = occluded[20:40] = True  # two runs with no marker labeled
    occluded[25, 0] = False  # ... the second one split by a label at frame 25
    points = np.full(40, 6)
    points[30:34] = MIN_POINTS - 1  # too few to be read as a subject: not counted
    assert unnamed_span(occluded, points, rate=10.0) == unnamed_span(occluded, points, rate=6.0)
    found = unnamed_span(occluded, points, rate=6.0)
    assert found is not None and (found.start, found.frames, found.points) == (26, 14, 6.0)  # 10 readable frames
    assert unnamed_span(occluded, points, rate=11.0) is None  # under a second's worth of readable frames
    assert unnamed_span(np.zeros((40, 2), bool), points, rate=6.0) is None


def _track(tmp_path: Path, positions: np.ndarray, rate: float) -> tuple[dict, str]:
    names = read_labeled(CMU).names
    write_c3d(tmp_path / "take.c3d", LabeledTrajectories(names, positions, np.isnan(positions).any(axis=2), rate))
    run = subprocess.run([sys.executable, "-m", "service.cli", "-q", "track", str(tmp_path / "take.c3d"), "--out",
                          str(tmp_path / "out.csv"), "--json"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout), run.stderr


def test_the_subject_away_is_the_longest_second_without_points_followed_by_labels() -> None:
    """A walk whose every marker left the view for 500 frames came back named from its shape
    before alone, 14-29 % right, and nothing said so."""
    occluded = np.zeros((60, 2), bool)
    points = np.full(60, 6)
    points[10:14] = 0  # under a second (rate 6 below: 6 frames) or not: the rate decides
    points[30:45] = 0
    occluded[30:45] = True
    assert away_span(occluded, points, rate=6.0) == (30, 15)
    assert away_span(occluded, points, rate=20.0) is None  # none lasts a second
    occluded[45:] = True  # nothing labeled after it: the unnamed span's warning, not this one
    points[45:] = 6
    assert away_span(occluded, points, rate=6.0) is None


def test_track_warns_when_a_subject_that_left_the_volume_comes_back_unnamed(tmp_path: Path) -> None:
    take = read_labeled(CMU)
    positions = take.positions[:240].copy()
    summary, stderr = _track(tmp_path, positions, take.rate)
    assert summary["unnamed_span"] is None and "no marker is labeled" not in stderr
    positions[100:120] = np.nan  # the subject leaves ...
    # ... and comes back 1.5 m away, not as a rigid copy of the body it left (stretched 30 %),
    # which the lost group's registration cannot find; as a rigid copy it is found and named
    centre = positions[120:].mean(axis=1, keepdims=True)
    positions[120:] = centre + 1.3 * (positions[120:] - centre) + [1500.0, 0.0, 0.0]
    summary, stderr = _track(tmp_path, positions, take.rate)
    assert summary["unnamed_span"] == {"start": 100, "frames": 140, "points": float(take.n_markers)}
    assert "warning: no marker is labeled in frames 100-239" in stderr and "--model" in stderr
