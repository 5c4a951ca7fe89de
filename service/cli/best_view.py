"""``markerflow best-view``: one camera per object and frame from any table of view costs.

The sliding-window DP of Jiang, Fels & Little (2008, Sec. III) on the costs of
COSTS.csv (``service.best_view.tables`` has both table formats), written to CHOICES.csv.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from formulations.best_view import select_views
from formulations.errors import FormulationError
from service.best_view.tables import read_view_costs, write_choices
from service.cli.output import check_writable_output
from service.cli.report import out
from service.errors import InputError
from service.words import counted


def run_best_view(costs_path: Path, output: Path, switch_cost: float, window: int) -> None:
    """Choose each object's camera per frame, write CHOICES.csv, print the switches.

    Raises:
        InputError: a bad table (``read_view_costs``), a negative switch cost, a window
            under one frame, or an output that cannot be written.
    """
    if not (np.isfinite(switch_cost) and switch_cost >= 0):
        raise InputError(f"--switch-cost must be a finite number >= 0, got {switch_cost}")
    if window < 1:
        raise InputError(f"--window must be at least 1 frame, got {window}")
    check_writable_output(output, costs_path, labeled=False)
    cameras, objects = read_view_costs(costs_path)
    try:
        chosen = [select_views(obj.costs[:, None, :], switch_cost, window)[:, 0] for obj in objects]
    except FormulationError as error:
        raise InputError(f"{costs_path}: {error}") from None
    write_choices(output, cameras, objects, chosen)
    switches = sum(int(np.count_nonzero(np.diff(views))) for views in chosen)
    greedy = sum(int(np.count_nonzero(np.diff(np.argmin(obj.costs, axis=1)))) for obj in objects)
    frames = sum(len(obj.frames) for obj in objects)
    out.print(
        f"{costs_path.name}: {counted(len(objects), 'object')}, {counted(len(cameras), 'camera')}, "
        f"{frames} object-frames -> {output} "
        f"({counted(switches, 'switch', 'switches')}; the per-frame best would switch {counted(greedy, 'time')})",
        highlight=False,
    )
