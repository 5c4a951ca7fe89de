"""A quick-look PNG of labeled trajectories: where a few markers went and when they were lost."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.typing import ColorType

from formulations.markers.runs import runs
from service.io.formats.replace_file import replacing
from service.io.recording import LabeledTrajectories, Recording

_AXIS_LABELS = ("x (mm)", "y (mm)", "z (mm)")
_COLOURS = matplotlib.color_sequences["tab10"]
_TRUTH_STYLE: dict[str, Any] = {"color": "0.55", "linewidth": 0.8, "zorder": 1}  # matplotlib keywords


def plot_trajectories(
    traj: LabeledTrajectories,
    path: str | os.PathLike[str],
    markers: list[str] | None = None,
    max_markers: int = 6,
    truth: Recording | None = None,
) -> Path:
    """Draw x, y and z over time for a few markers, with their occlusions, to a PNG.

    Args:
        traj: The labeled trajectories to draw.
        path: Where to write the PNG; missing parent folders are created.
        markers: Labels to draw, all of them (``max_markers`` does not apply). By default the
            ``max_markers`` most often occluded markers, ties in column order.
        max_markers: How many markers the default choice takes.
        truth: Optional ground truth, drawn as thin grey lines under the markers
            it shares a name with.

    Returns:
        The path written.

    Raises:
        ValueError: If a requested marker is not in ``traj`` or nothing would be drawn.
        InputError: The PNG cannot be written (an earlier file there is left as it was: it is
            written beside it and renamed onto it whole, so a Ctrl-C cannot leave it cut).
    """
    columns = _choose_columns(traj, markers, max_markers)
    fig = Figure(figsize=(11.0, 8.5), layout="constrained")
    FigureCanvasAgg(fig)  # a bare Agg canvas: no display, no pyplot global state
    axes = fig.subplots(4, 1, sharex=True, height_ratios=[3, 3, 3, 0.4 + 0.25 * len(columns)])
    seconds = np.arange(traj.n_frames) / traj.rate
    # Blank occluded samples even if a producer left stale coordinates there.
    shown = np.where(traj.occluded[:, columns, None], np.nan, traj.positions[:, columns])
    for dim, ax in enumerate(axes[:3]):
        if truth is not None:
            _draw_truth(ax, truth, [traj.names[k] for k in columns], dim)
        for slot in range(len(columns)):
            ax.plot(seconds, shown[:, slot, dim], color=_colour(slot), linewidth=1.3)
        ax.set_ylabel(_AXIS_LABELS[dim])
        ax.grid(alpha=0.3)
    _draw_occlusions(axes[3], traj, columns)
    _add_legend(fig, [traj.names[k] for k in columns], truth is not None)
    fig.suptitle(_title(traj))
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    with replacing(out, ".png") as temp:
        fig.savefig(temp, format="png", dpi=100)
    return out


def _choose_columns(
    traj: LabeledTrajectories, markers: list[str] | None, max_markers: int
) -> list[int]:
    """Column indices to draw, in column order."""
    if markers is None:
        if max_markers < 1:
            raise ValueError(f"max_markers must be at least 1, got {max_markers}")
        # The most occluded markers are the ones a reviewer wants to check.
        by_loss = np.argsort(-traj.occluded.sum(axis=0), kind="stable")
        return sorted(int(k) for k in by_loss[:max_markers])
    unknown = [name for name in markers if name not in traj.names]
    if unknown:
        raise ValueError(f"unknown marker(s): {', '.join(unknown)}")
    if not markers:
        raise ValueError("no markers to plot")
    return sorted({traj.names.index(name) for name in markers})


def _colour(slot: int) -> ColorType:
    return _COLOURS[slot % len(_COLOURS)]


def _draw_truth(ax: Axes, truth: Recording, names: list[str], dim: int) -> None:
    seconds = np.arange(truth.n_frames) / truth.rate
    for name in names:
        if name in truth.names:
            ax.plot(seconds, truth.positions[:, truth.names.index(name), dim], **_TRUTH_STYLE)


def _draw_occlusions(ax: Axes, traj: LabeledTrajectories, columns: list[int]) -> None:
    """One row per marker, a bar wherever it is occluded, its share in the row label."""
    frame = 1.0 / traj.rate
    for row, k in enumerate(columns):
        # Bars are centred on samples; the edge line keeps one-frame gaps visible.
        spans = [(start * frame - frame / 2, length * frame) for start, length in runs(traj.occluded[:, k])]
        colour = _colour(row)
        ax.broken_barh(spans, (row - 0.35, 0.7), facecolor=colour, edgecolor=colour)
    ax.set_yticks(
        range(len(columns)),
        [f"{traj.names[k]} {100 * traj.occluded[:, k].mean():.0f}%" for k in columns],
        fontsize=8,
    )
    ax.set_ylim(len(columns) - 0.5, -0.5)
    ax.set_xlim(-frame / 2, (traj.n_frames - 0.5) * frame)
    ax.set_ylabel("occluded")
    ax.set_xlabel("time (s)")


def _add_legend(fig: Figure, names: list[str], with_truth: bool) -> None:
    handles = [Line2D([], [], color=_colour(slot), linewidth=2) for slot in range(len(names))]
    labels = list(names)
    if with_truth:
        handles.append(Line2D([], [], **_TRUTH_STYLE))
        labels.append("truth")
    fig.legend(handles, labels, loc="outside right upper")


def _title(traj: LabeledTrajectories) -> str:
    share = 100 * traj.occluded.mean() if traj.occluded.size else 0.0
    return (
        f"{traj.n_frames} frames at {traj.rate:g} Hz, {len(traj.names)} markers, "
        f"{share:.1f}% of marker-frames occluded"
    )
