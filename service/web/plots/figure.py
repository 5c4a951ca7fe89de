"""A matplotlib figure without pyplot, and its SVG bytes."""

from __future__ import annotations

import io

from matplotlib.backends.backend_svg import FigureCanvasSVG
from matplotlib.figure import Figure


def new_figure(width: float, height: float) -> Figure:
    """A figure on its own SVG canvas (no pyplot state, so request threads do not share one)."""
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasSVG(figure)
    return figure


def svg_bytes(figure: Figure, title: str) -> bytes:
    """The figure as SVG with ``title`` in its metadata; text is drawn as paths (matplotlib's
    default ``svg.fonttype``), so the page needs no font. The page's ``alt`` text describes it."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="svg", metadata={"Title": title, "Date": None})
    return buffer.getvalue()
