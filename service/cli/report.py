"""How the CLI shows figures and progress."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

# Piped output (files, CI logs) has no width to detect: give tables room rather than 80 columns.
out = Console() if sys.stdout.isatty() else Console(width=120)
err = Console(stderr=True)

LABELS = {
    "label_accuracy": ("label accuracy", "{:.4%}"),
    "swaps": ("label swaps", "{}"),
    "ghost_precision": ("ghost precision", "{:.3f}"),
    "ghost_recall": ("ghost recall", "{:.3f}"),
    "integral_window_fraction": ("integral windows", "{:.1%}"),
    "gap_median": ("median gap", "{:.2e}"),
    "gap_max": ("max gap", "{:.2e}"),
    "seconds_per_frame": ("ms per frame", None),
    "frames": ("frames", "{}"),
    "markers": ("markers", "{}"),
    "formulation": ("formulation", "{}"),
    "rmse_mm": ("3D RMSE (mm)", "{:.2f}"),
    "filled_rmse_mm": ("filled RMSE (mm)", "{:.2f}"),
}


def print_summary(summary: dict, title: str) -> None:
    """A two-column table of the figures in ``summary``."""
    table = Table(title=title, show_header=False)
    for key, value in summary.items():
        label, fmt = LABELS.get(key, (key, "{}"))
        if value is None:
            text = "none proven" if key.startswith("gap") else "-"
        elif key == "seconds_per_frame":
            text = f"{1000 * value:.2f}"
        else:
            text = fmt.format(value)
        table.add_row(label, text)
    out.print(table)


@contextmanager
def window_progress(description: str) -> Iterator[Callable[[int, int], None] | None]:
    """A progress bar over windows on stderr (nothing when stderr is not a terminal)."""
    if not err.is_terminal:
        yield None
        return
    columns = (TextColumn(description), BarColumn(), MofNCompleteColumn(), TextColumn("windows"), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task(description, total=None)

        def advance(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield advance
