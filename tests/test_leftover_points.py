"""Nothing the input carried is lost: the points no marker took become unlabeled trajectories
(``*N``), and a file's own unlabeled trajectories are points to label, not markers."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from test_cli import CMU, cmu_points, run_cli, write_c3d

from service.labeling.leftover_points import leftover_points, reach_from_labels, unlabeled_channels


def _moving(start: np.ndarray, step: np.ndarray, frames: int) -> np.ndarray:
    return start + np.arange(frames)[:, None] * step


def test_every_point_no_marker_took_is_kept_exactly_once() -> None:
    rng = np.random.default_rng(3)
    points = [rng.uniform(0, 2000, (rng.integers(0, 9), 3)) for _ in range(40)]
    taken = np.full((40, 5), -1)
    for f, cloud in enumerate(points):
        chosen = rng.permutation(len(cloud))[: min(len(cloud), rng.integers(0, 6))]
        taken[f, : len(chosen)] = chosen
    channels = unlabeled_channels(leftover_points(points, taken), reach=30.0)
    for f, cloud in enumerate(points):
        left = np.delete(cloud, taken[f][taken[f] >= 0], axis=0)
        kept = channels[f][np.isfinite(channels[f]).all(axis=1)]
        assert Counter(map(tuple, kept)) == Counter(map(tuple, left))


def test_a_moving_point_stays_one_trajectory_and_a_flash_is_its_own() -> None:
    frames = 30
    a, b = _moving(np.zeros(3), np.array([6.0, 0, 0]), frames), _moving(np.full(3, 500.0), np.array([0, -6.0, 0]), frames)
    leftover = [np.vstack([a[f], b[f]] + ([np.full(3, 1500.0)] if f == 12 else [])) for f in range(frames)]
    channels = unlabeled_channels(leftover, reach=20.0)
    held = np.isfinite(channels).all(axis=2)
    whole = [c for c in range(channels.shape[1]) if held[:, c].all()]
    assert len(whole) == 2  # a and b each in one channel from first frame to last
    assert {tuple(channels[0, c]) for c in whole} == {tuple(a[0]), tuple(b[0])}
    assert all(np.allclose(channels[:, c], a) or np.allclose(channels[:, c], b) for c in whole)
    assert channels.shape[1] == 3 and held.sum() == 2 * frames + 1


@pytest.mark.parametrize("gap,channels", [(0, 2), (1, 1)])
def test_fragments_share_a_channel_only_with_an_empty_frame_between(gap: int, channels: int) -> None:
    """Two fragments far apart, the second starting ``gap`` frames after the first ends."""
    first = [np.zeros((1, 3))] * 5
    second = [np.full((1, 3), 900.0)] * 5
    leftover = first + [np.zeros((0, 3))] * gap + second
    assert unlabeled_channels(leftover, reach=20.0).shape[1] == channels


def test_channels_are_as_few_as_the_most_fragments_alive_at_once() -> None:
    """Random far-apart fragments: the packing is optimal (interval partitioning)."""
    rng = np.random.default_rng(5)
    frames, spans = 60, [(int(s), int(s + rng.integers(1, 12))) for s in rng.integers(0, 50, 25)]
    leftover = [np.array([[1000.0 * i, 0, 0] for i, (s, e) in enumerate(spans) if s <= f < e]).reshape(-1, 3)
                for f in range(frames)]
    # a fragment keeps its channel one frame past its end: those spans may not overlap
    alive = max(sum(s <= f < e + 1 for s, e in spans) for f in range(frames))
    assert unlabeled_channels(leftover, reach=20.0).shape[1] == alive


def test_reach_follows_the_take_motion() -> None:
    slow = _moving(np.zeros(3), np.array([2.0, 0, 0]), 50)[:, None]
    fast = _moving(np.zeros(3), np.array([40.0, 0, 0]), 50)[:, None]
    assert reach_from_labels(slow) == pytest.approx(10.0) and reach_from_labels(fast) == pytest.approx(80.0)


def test_a_files_own_unlabeled_trajectory_is_labeled_or_kept_not_refused(tmp_path: Path) -> None:
    """A Vicon-style ``*7`` absent in frame 0 was taken for a marker, and the take refused."""
    labels, points = cmu_points(120)
    fragment = np.full((3, 1, 120), np.nan)
    fragment[:, 0, 40:90] = points[:, 0, 40:90] + np.array([[300.0], [0.0], [0.0]])  # a point track off the body
    source = write_c3d(tmp_path / "in.c3d", labels + ["*7"], np.concatenate([points, fragment], axis=1))
    result = run_cli("-q", "track", source, "--out", tmp_path / "out.c3d", "--json")
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["markers"] == len(labels) and summary["unlabeled_points"] == 50
    out = ezc3d.c3d(str(tmp_path / "out.c3d"))
    written = list(out["parameters"]["POINT"]["LABELS"]["value"])
    assert written == labels + ["*7"]  # the input's *7, emptied by the relabel, holds what no marker took
    residuals = out["data"]["meta_points"]["residuals"][0]
    kept = out["data"]["points"][:3, len(labels)]
    assert np.allclose(kept[:, 40:90], fragment[:, 0, 40:90], atol=1e-3) and (residuals[len(labels), :40] < 0).all()
    said = run_cli("track", source, "--out", tmp_path / "again.c3d")  # the summary line says so
    assert "50 points no marker took kept as 1 unlabeled trajectory *N" in " ".join(said.stdout.split())
    table = run_cli("track", source, "--out", tmp_path / "again.trc")  # a TRC holds labels only, and says so
    assert "50 points no marker took are not in this table" in " ".join(table.stdout.split())


def test_cmu_relabeled_whole_keeps_no_unlabeled_trajectory(tmp_path: Path) -> None:
    """A clean take: every point is a marker's, so no ``*N`` is written."""
    result = run_cli("-q", "track", CMU, "--out", tmp_path / "out.c3d", "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["unlabeled_points"] == 0
    labels = list(ezc3d.c3d(str(tmp_path / "out.c3d"))["parameters"]["POINT"]["LABELS"]["value"])
    assert not any(label.startswith("*") for label in labels)


def test_the_frames_after_end_keep_the_inputs_points_unlabeled(tmp_path: Path) -> None:
    result = run_cli("-q", "track", CMU, "--out", tmp_path / "out.c3d", "--end", "200")
    assert result.returncode == 0, result.stderr
    before, after = ezc3d.c3d(str(CMU)), ezc3d.c3d(str(tmp_path / "out.c3d"))
    markers = before["header"]["points"]["size"]
    assert [str(label)[0] for label in after["parameters"]["POINT"]["LABELS"]["value"][markers:]] == ["*"] * markers
    assert (after["data"]["meta_points"]["residuals"][0, :markers, 200:] < 0).all()  # labels only where labeled
    # each marker's input samples from frame 200 on, as it was, in its own unlabeled trajectory
    assert np.array_equal(after["data"]["points"][:3, markers:, 200:], before["data"]["points"][:3, :, 200:])
