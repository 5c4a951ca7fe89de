"""How the CLI shows figures and progress."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from service.labeling.result_warnings import doubtful_warning

# Piped output (files, CI logs) has no width to detect: give tables room rather than 80
# columns, and never break a line of text (a script reads the summary as one line).
out = Console() if sys.stdout.isatty() else Console(width=120, soft_wrap=True)
err = Console(stderr=True)
quiet = False  # ``markerflow --quiet``: no progress; results are still printed
PLAIN_EVERY_SECONDS = 10.0  # piped progress: a line at least this often,
PLAIN_LINES = 10  # and about this many lines per run

CERTIFICATE = "optimal under the model"  # what an integral window proves: not that its labels are right
NO_CERTIFICATE = "none: this formulation proves no bound on any window"  # nn-hungarian, dp-sequential, mht's cut search

LABELS = {
    "label_accuracy": ("label accuracy", "{:.4%}"),
    "marker_frames": ("marker-frames scored", "{}"),
    "correct": ("labeled right", "{}"),
    "missed": ("left unlabeled", "{}"),
    "swaps": ("label swaps", "{}"),
    "ghost_precision": ("ghost precision", "{:.3f}"),
    "ghost_recall": ("ghost recall", "{:.3f}"),
    "integral_window_fraction": (f"windows {CERTIFICATE}", "{:.1%}"),
    "doubtful_fraction": ("doubtful labels", "{:.1%}"),
    "doubtful_share": ("doubtful labels (scored frames)", "{:.2%}"),
    "doubtful_recall": ("wrong labels flagged doubtful", "{:.1%}"),
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
    """A two-column table of the figures in ``summary``, captioned with what the certificate proves."""
    caption = f"an integral window is {CERTIFICATE} (proven best for its costs), not proven right"
    table = Table(title=title, caption=caption, show_header=False)
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


def warn_doubtful(fraction: float | None) -> None:
    """``eval``'s stderr line when more than ``DOUBTFUL_WARNING`` of the labels are doubtful: it
    writes no labels to check, so the line says where they are."""
    warn(doubtful_warning(fraction, "markerflow track writes them with each label's confidence"))


def stage(line: str) -> None:
    """What long work comes next, a line on stderr unless quiet: after its last window a long
    take assembles and writes for tens of seconds (50,000 frames: 35 s), silent before."""
    if not quiet:
        err.print(line, highlight=False, soft_wrap=True, markup=False)


def warn(line: str | None) -> None:
    """A warning line on stderr (none for None), after the figures it qualifies."""
    if line is not None:
        sys.stdout.flush()
        print(line, file=sys.stderr, flush=True)


@contextmanager
def window_progress(description: str) -> Iterator[Callable[[int, int], None] | None]:
    """Progress over windows on stderr: a bar on a terminal, plain lines when piped, none if quiet."""
    if quiet:
        yield None
    elif err.is_terminal:
        with _bar(description) as advance:
            yield advance
    else:
        yield _plain_lines(description)


@contextmanager
def _bar(description: str) -> Iterator[Callable[[int, int], None]]:
    columns = (TextColumn(description), BarColumn(), MofNCompleteColumn(), TextColumn("windows"), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task(description, total=None)

        def advance(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield advance


def _plain_lines(description: str) -> Callable[[int, int], None]:
    """``description: 40/180 windows, 12 s`` after every tenth of the windows, every
    ``PLAIN_EVERY_SECONDS`` and the last window, flushed: a log shows it as it happens."""
    began = time.monotonic()
    last = (began, 0)

    def advance(done: int, total: int) -> None:
        nonlocal last
        now = time.monotonic()
        step = max(1, -(-total // PLAIN_LINES))
        if done == total or done - last[1] >= step or now - last[0] >= PLAIN_EVERY_SECONDS:
            print(f"{description}: {done}/{total} windows, {now - began:.0f} s", file=sys.stderr, flush=True)
            last = (now, done)

    return advance
