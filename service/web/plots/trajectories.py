"""Trajectories of chosen markers over time: one panel per marker, x, y and z told apart by line style."""

from __future__ import annotations

import numpy as np

from service.web.job_data import Labels
from service.web.plots.figure import new_figure, svg_bytes

AXES = (("x", "-"), ("y", "--"), ("z", ":"))
DEFAULT_MARKERS = 3
MAX_MARKERS = 8


def chosen_markers(labels: Labels, asked: list[str]) -> list[str]:
    """The markers asked for that exist (at most ``MAX_MARKERS``); by default the most often
    occluded ones, which a reviewer wants to check first."""
    known = [name for name in asked if name in labels.names][:MAX_MARKERS]
    if known:
        return known
    by_loss = np.argsort(-labels.occluded.sum(axis=0), kind="stable")[:DEFAULT_MARKERS]
    return [labels.names[m] for m in sorted(by_loss)]


def trajectories_svg(labels: Labels, markers: list[str]) -> bytes:
    """Each marker's x, y, z in mm over seconds; samples it did not see are gaps in the lines
    (the filled prediction is not drawn as data), and doubtful samples carry a ``|`` tick."""
    seconds = (labels.first_frame + np.arange(labels.occluded.shape[0])) / labels.rate  # the take's time
    figure = new_figure(9.0, 0.6 + 1.7 * len(markers))
    panels = np.atleast_1d(figure.subplots(len(markers), 1, sharex=True))
    for axes, name in zip(panels, markers):
        m = labels.names.index(name)
        shown = np.where(labels.occluded[:, m, None], np.nan, labels.positions[:, m])
        for dim, (axis, style) in enumerate(AXES):
            axes.plot(seconds, shown[:, dim], style, color="0.1", linewidth=1.0, label=axis)
            doubtful = labels.doubtful[:, m]
            axes.plot(seconds[doubtful], shown[doubtful, dim], "|", color="#e66100", markersize=7,
                      label="doubtful" if dim == 0 else None)
        axes.set_ylabel(f"{name} (mm)", fontsize=8)
        axes.grid(alpha=0.3)
    panels[0].legend(loc="upper right", ncols=4, fontsize=7)
    panels[-1].set_xlabel("time (s)")
    title = "trajectories of " + ", ".join(markers)
    figure.suptitle(title, fontsize=10)
    return svg_bytes(figure, title)
