"""The per-window certificate chart: LP gap, integrality and solve time of every window."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Patch

from service.labeling.stats import WindowStats
from service.web.plots.figure import new_figure, svg_bytes

FRACTIONAL_HATCH = "////"
MANY_WINDOWS = 300  # past this a bar of an 8-inch chart is under a pixel wide
INTEGRAL = Patch(facecolor="0.35", label="integral (solid)")
FRACTIONAL = Patch(facecolor="white", edgecolor="0.1", hatch=FRACTIONAL_HATCH, label="fractional (hatched)")


def certificate_svg(windows: list[WindowStats], total: int | None = None) -> bytes:
    """Two panels over the window index: the relative gap (cost - bound) / cost, and the solve
    time. An integral window is a solid bar (its gap is 0: the labels are optimal under the
    model); a fractional one is hatched; a window with no proven bound (a heuristic's) is an
    ``x`` at the top of the gap panel. ``total``: the job's windows, when more are to come
    (a running job): the title then says how many are done, not "149 of 149" of 299."""
    figure = new_figure(8.0, 4.2)
    gap_axes, time_axes = figure.subplots(2, 1, sharex=True)
    index = np.arange(len(windows))
    integral = np.array([w.integral for w in windows], dtype=bool)
    gaps = np.array([w.gap for w in windows], dtype=float)
    proven = np.isfinite(gaps)
    seconds = np.array([w.solve_seconds for w in windows], dtype=float)
    for axes, values, label in ((gap_axes, np.where(proven, gaps, 0.0), "LP gap"), (time_axes, seconds, "solve (s)")):
        _bars(axes, index, values, integral)
        axes.set_ylabel(label)
        axes.grid(axis="y", alpha=0.3)
    fractional_gaps = gaps[proven & ~integral]
    top = float(fractional_gaps.max()) if fractional_gaps.size and fractional_gaps.max() > 0 else 1.0
    gap_axes.set_ylim(0, top * 1.15)
    keys = [INTEGRAL, FRACTIONAL]
    if (~proven).any():
        keys += gap_axes.plot(index[~proven], np.full((~proven).sum(), top * 1.05), "kx", label="no bound proven")
    coming = total is not None and total > len(windows)
    if len(windows) and integral.all():
        gap_axes.text(0.5, 0.5, f"every window {'so far ' if coming else ''}integral: gap 0", transform=gap_axes.transAxes,
                      ha="center", va="center")
    gap_axes.legend(handles=keys, loc="upper right", fontsize=8)
    time_axes.set_xlabel("window")
    if len(windows):
        time_axes.set_xlim(-0.6, len(windows) - 0.4)
    title = f"{int(integral.sum())} of {len(windows)} windows integral"
    if coming:
        title += f" ({len(windows)} of {total} done)"
    figure.suptitle(title)
    return svg_bytes(figure, title)


def _bars(axes: Axes, index: np.ndarray, values: np.ndarray, integral: np.ndarray) -> None:
    """A bar per window, solid where integral and hatched where fractional; past
    ``MANY_WINDOWS`` (a bar under a pixel wide) one stepped outline per kind, since a patch per
    window made a 2,632-window job's chart take 2.8 s, the server's other requests waiting."""
    if len(index) <= MANY_WINDOWS:
        axes.bar(index[integral], values[integral], width=0.8, color=INTEGRAL.get_facecolor())
        axes.bar(index[~integral], values[~integral], width=0.8, color="white", edgecolor="0.1", hatch=FRACTIONAL_HATCH)
        return
    axes.fill_between(index, np.where(integral, values, 0.0), step="mid", linewidth=0, color=INTEGRAL.get_facecolor())
    axes.fill_between(index, np.where(integral, 0.0, values), step="mid", facecolor="white", edgecolor="0.1",
                      hatch=FRACTIONAL_HATCH, linewidth=0.5)
