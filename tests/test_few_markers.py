"""A take of one to four markers is labeled: the rigid, mirror and turn repairs, which need a
triangle or a quadruple of markers, have nothing to do with fewer and must step aside."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from formulations.markers.mirror import LearnedPairs, rigid_groups
from formulations.markers.reacquire import refine_by_segment
from formulations.markers.state import MarkerState
from service.capture.capture import Capture
from service.io.formats import read_labeled
from service.labeling.capture_labeling import CaptureLabeling

BTS = Path(__file__).resolve().parents[2] / "shared" / "data" / "c3d_ezc3d_testfiles" / "BTS.c3d"
CORNERS = np.array([[0.0, 0, 0], [80, 0, 0], [0, 60, 0], [20, 30, 70]])


def moving_cloud(k: int, frames: int = 80, seed: int = 0) -> np.ndarray:
    """``(frames, k, 3)``: the first ``k`` corners of a rigid body turning and translating, with noise."""
    rng = np.random.default_rng(seed)
    out = np.empty((frames, k, 3))
    for f in range(frames):
        a = 0.02 * f
        turn = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        out[f] = CORNERS[:k] @ turn.T + [3.0 * f, 0.5 * f, 0]
    return out + rng.normal(0, 0.5, out.shape)


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_one_to_four_markers_are_labeled_right_through_gaps_and_stray_points(k):
    truth = moving_cloud(k)
    gone = np.zeros(truth.shape[:2], dtype=bool)
    gone[20:31, 0] = True  # each marker leaves for a while and comes back
    gone[45:50, min(1, k - 1)] |= k > 1
    rng = np.random.default_rng(1)
    points = []
    for f in range(len(truth)):
        stray = truth[f, :1] + [400.0, 300.0, 0.0] + rng.normal(0, 20, (2, 3))  # unnamed points far away
        shown = np.vstack([truth[f][~gone[f]], stray])
        points.append(shown[rng.permutation(len(shown))])
    capture = Capture([f"m{i}" for i in range(k)], truth[0], 100.0, points=points)

    result, _ = CaptureLabeling(capture).label()

    np.testing.assert_array_equal(result.occluded, gone)
    np.testing.assert_allclose(result.positions[~gone], truth[~gone])


@pytest.mark.parametrize("n", [1, 2, 3])
def test_too_few_markers_form_no_rigid_group(n):
    state = MarkerState.from_first_frame(CORNERS[:n])
    for size in range(n + 1, 5):  # a triangle or a quadruple of more markers than there are
        groups, found = rigid_groups(np.ones(n, dtype=bool), LearnedPairs.of(state), 1e9, size)
        assert groups.shape == (n, size) and not found.any()


def test_a_lone_marker_has_no_neighbourhood_to_register():
    state = MarkerState.from_first_frame(CORNERS[:1])
    guess = state.position.copy()
    moved = refine_by_segment(guess, np.array([True]), state.neighbours, state.distance_var, CORNERS + 5.0)
    np.testing.assert_array_equal(moved, guess)


@pytest.mark.skipif(not BTS.exists(), reason="shared ezc3d test files not present")
@pytest.mark.parametrize("start,markers", [(239, 1), (241, 2)])
def test_bts_from_a_frame_with_one_or_two_markers(tmp_path, start, markers):
    out = tmp_path / "x.trc"
    run = subprocess.run(
        [sys.executable, "-m", "service.cli", "-q", "track", str(BTS), "--start", str(start), "--end", "300",
         "--json", "-o", str(out)],
        capture_output=True, text=True, timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert json.loads(run.stdout)["markers"] == markers
    labeled, source = read_labeled(out), read_labeled(BTS)
    present = ~source.missing()[start]
    for name in np.array(source.names)[present]:
        column = labeled.names.index(name)
        truth = source.positions[start:300, source.names.index(name)]
        got = labeled.positions[:, column]
        seen = ~np.isnan(got).any(axis=1)
        assert seen.mean() > 0.9
        np.testing.assert_allclose(got[seen], truth[seen], atol=1e-3)
