"""The trajectory plot writes a readable PNG and names bad requests."""

from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from service.evaluation.plot import plot_trajectories
from service.evaluation.scene import generate_scene
from service.io.recording import LabeledTrajectories, Recording

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def truth() -> Recording:
    return generate_scene(n_frames=120)


@pytest.fixture
def traj(truth: Recording) -> LabeledTrajectories:
    occluded = np.zeros(truth.positions.shape[:2], dtype=bool)
    occluded[20:50, truth.names.index("LTOE")] = True
    occluded[:, truth.names.index("RFIN")] = True
    positions = np.where(occluded[..., None], np.nan, truth.positions)
    return LabeledTrajectories(truth.names, positions, occluded, truth.rate)


def _assert_real_png(path: Path) -> None:
    assert path.read_bytes()[:8] == PNG_MAGIC
    pixels = imread(path)
    assert (pixels != pixels[0, 0]).any(), "the image is a single flat colour"


def test_writes_png(traj: LabeledTrajectories, tmp_path: Path) -> None:
    out = plot_trajectories(traj, tmp_path / "plot.png")
    assert out == tmp_path / "plot.png"
    _assert_real_png(out)


def test_truth_overlay_and_new_folder(
    traj: LabeledTrajectories, truth: Recording, tmp_path: Path
) -> None:
    out = plot_trajectories(traj, str(tmp_path / "new" / "plot.png"), truth=truth)
    _assert_real_png(out)


def test_all_occluded_marker(traj: LabeledTrajectories, tmp_path: Path) -> None:
    out = plot_trajectories(traj, tmp_path / "plot.png", markers=["RFIN", "LTOE"])
    _assert_real_png(out)


def test_unknown_marker_is_named(traj: LabeledTrajectories, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="NOPE"):
        plot_trajectories(traj, tmp_path / "plot.png", markers=["LTOE", "NOPE"])
    assert not (tmp_path / "plot.png").exists()


@pytest.mark.parametrize("markers, max_markers", [([], 6), (None, 0)])
def test_nothing_to_draw_raises(
    traj: LabeledTrajectories, tmp_path: Path, markers: list[str] | None, max_markers: int
) -> None:
    with pytest.raises(ValueError):
        plot_trajectories(traj, tmp_path / "plot.png", markers=markers, max_markers=max_markers)
