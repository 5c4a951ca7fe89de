"""The trajectory plot writes a readable PNG, draws the truth under the markers, and names
bad requests."""

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.colors import same_color
from matplotlib.figure import Figure
from matplotlib.image import imread
from matplotlib.lines import Line2D

from service.evaluation import plot
from service.evaluation.plot import plot_trajectories
from service.evaluation.scene import generate_scene
from service.io.recording import LabeledTrajectories, Recording

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
TRUTH_GREY = "0.55"


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


@pytest.fixture
def figures(monkeypatch: pytest.MonkeyPatch) -> list[Figure]:
    """Every Figure the plot module makes, to read its artists after the PNG is written."""
    made: list[Figure] = []

    class KeptFigure(Figure):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(plot, "Figure", KeptFigure)
    return made


def _grey_lines(fig: Figure) -> list[list[Line2D]]:
    """Per x/y/z axes, the lines in the truth's grey."""
    return [[line for line in ax.get_lines() if same_color(line.get_color(), TRUTH_GREY)] for ax in fig.axes[:3]]


def _drawn_names(fig: Figure) -> list[str]:
    """The markers drawn, from the occlusion axes' row labels (``"LTOE 25%"``)."""
    return [label.get_text().split()[0] for label in fig.axes[3].get_yticklabels()]


def _assert_real_png(path: Path) -> None:
    assert path.read_bytes()[:8] == PNG_MAGIC
    pixels = imread(path)
    assert (pixels != pixels[0, 0]).any(), "the image is a single flat colour"


def test_writes_png(traj: LabeledTrajectories, tmp_path: Path, figures: list[Figure]) -> None:
    out = plot_trajectories(traj, tmp_path / "plot.png")
    assert out == tmp_path / "plot.png"
    _assert_real_png(out)
    (fig,) = figures
    assert _grey_lines(fig) == [[], [], []]  # no truth given, none drawn


def test_truth_overlay_and_new_folder(
    traj: LabeledTrajectories, truth: Recording, tmp_path: Path, figures: list[Figure]
) -> None:
    out = plot_trajectories(traj, str(tmp_path / "new" / "plot.png"), truth=truth)
    _assert_real_png(out)
    (fig,) = figures
    names = _drawn_names(fig)
    assert {"LTOE", "RFIN"} <= set(names)  # the two occluded markers are among the six drawn
    seconds = np.arange(truth.n_frames) / truth.rate
    for dim, (ax, grey) in enumerate(zip(fig.axes[:3], _grey_lines(fig))):
        # One grey line per drawn marker: its true coordinate over time, under the marker's own line.
        assert len(grey) == len(names)
        for line, name in zip(grey, names):
            np.testing.assert_array_equal(line.get_xdata(), seconds)
            np.testing.assert_array_equal(line.get_ydata(), truth.positions[:, truth.names.index(name), dim])
        coloured = [line for line in ax.get_lines() if line not in grey]
        assert len(coloured) == len(names)
        assert max(line.get_zorder() for line in grey) < min(line.get_zorder() for line in coloured)
    assert "truth" in [text.get_text() for text in fig.legends[0].get_texts()]


def test_truth_only_for_markers_it_names(
    traj: LabeledTrajectories, truth: Recording, tmp_path: Path, figures: list[Figure]
) -> None:
    keep = [k for k, name in enumerate(truth.names) if name != "LTOE"]
    partial = Recording([truth.names[k] for k in keep], truth.positions[:, keep], truth.rate)
    plot_trajectories(traj, tmp_path / "plot.png", markers=["RFIN", "LTOE"], truth=partial)
    (fig,) = figures
    rfin = partial.positions[:, partial.names.index("RFIN")]
    for dim, grey in enumerate(_grey_lines(fig)):
        (line,) = grey  # LTOE has no truth to draw
        np.testing.assert_array_equal(line.get_ydata(), rfin[:, dim])


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
