"""The occlusion and doubt timeline: one row per marker, one column per frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.patches import Patch

from formulations.markers.runs import runs
from service.web.job_data import Labels
from service.web.plots.figure import new_figure, svg_bytes


@dataclass(frozen=True)
class State:
    """How a label state is drawn: a fill light or dark enough to tell apart in grey, and a hatch."""

    name: str
    colour: str
    hatch: str


# Orange and purple stay apart for the common colour-vision deficiencies; the hatches and the
# grey levels keep them apart in print too.
SEEN = State("seen", "#d0d0d0", "")
DOUBTFUL = State("doubtful", "#e66100", "xxx")
FILLED = State("filled (occluded, predicted)", "#5d3a9b", "////")
OCCLUDED = State("occluded", "white", "...")


def state_masks(labels: Labels) -> list[tuple[State, np.ndarray]]:
    """Each state's ``(F, M)`` mask; every sample is in exactly one."""
    seen = ~labels.occluded
    return [(SEEN, seen & ~labels.doubtful), (DOUBTFUL, seen & labels.doubtful),
            (FILLED, labels.filled), (OCCLUDED, labels.occluded & ~labels.filled)]


def timeline_svg(labels: Labels) -> bytes:
    """Markers x frames, each run of one state a bar with that state's fill and hatch."""
    n_frames, n_markers = labels.occluded.shape
    figure = new_figure(10.0, 1.4 + 0.2 * n_markers)
    axes = figure.subplots()
    for state, mask in state_masks(labels):
        for m in range(n_markers):
            spans = runs(mask[:, m])
            if spans:
                axes.broken_barh([(labels.first_frame + start - 0.5, length) for start, length in spans], (m - 0.42, 0.84),
                                 facecolor=state.colour, edgecolor="0.25", linewidth=0.3, hatch=state.hatch)
    axes.set_yticks(range(n_markers), labels.names, fontsize=7)
    axes.set_ylim(n_markers - 0.5, -0.5)
    axes.set_xlim(labels.first_frame - 0.5, labels.first_frame + n_frames - 0.5)
    axes.set_xlabel(f"frame of the take ({labels.rate:g} Hz)")
    keys = [Patch(facecolor=state.colour, edgecolor="0.25", hatch=state.hatch, label=state.name) for state, _ in
            state_masks(labels)]
    figure.legend(handles=keys, loc="outside upper center", ncols=4, fontsize=8)
    return svg_bytes(figure, "labels per marker and frame")
