"""The accuracy matrix of issue 11: real recordings x conditions x seeds x formulations.

Every labeled take of ../shared/data (service/evaluation/matrix.py lists them, with the
fixed tuning/validation split and the conditions) is simulated, labeled and scored. Prints
one table per half, a summary, and issue 11's goals on the validation rows. Tune on the
tuning half only. Takes with real gaps keep them: they add to the simulated deletions.

    .venv/bin/python bench/accuracy_matrix.py [--half both] [--recordings ...] [--conditions ...]
        [--seeds 0 1 2] [--formulations lp-l1 nn-hungarian] [--frames 0] [--jobs 2] [--json cells.json] [--mht-reading]
        [--frame-step 1]

Columns per formulation: acc % (pooled over seeds), known (the same without the marker-frames
where the file's own label jumps to another marker, ``service/evaluation/label_jumps.py``:
there its truth is not known), swaps, vdo (visible marker-frames
declared occluded), ghost (marker-frames labeled with a ghost), ms/frame (labeling only),
min and last 1,000-frame block accuracy %. Counts are summed over the seeds. A cell whose
labeling raises is listed as FAILED CELL at the end (and under "failed" in the JSON).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import asdict, astuple, dataclass
from functools import partial
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from service.evaluation.matrix import (  # noqa: E402
    BASELINE,
    CONDITIONS,
    DATA,
    HALVES,
    RECORDINGS,
    Cell,
    CellKey,
    Take,
    prepare,
    run_cell,
)
from service.evaluation.matrix_summary import Goal, Row, aggregate, goals  # noqa: E402

_COLUMNS = f"{'acc %':>7s} {'known':>6s} {'swaps':>5s} {'vdo':>5s} {'ghost':>5s} {'ms/f':>5s} {'min blk':>7s} {'last':>6s}"


def main() -> None:
    args = _arguments()
    takes = [prepare(r, args.data, args.frame_step) for r in RECORDINGS
             if (args.half in ("both", r.half)) and (not args.recordings or r.name in args.recordings)]
    _print_takes(takes, args.frames)
    keys = [CellKey(t.recording.name, c, s, f)
            for t in takes for c in args.conditions for s in args.seeds for f in args.formulations]
    cells, failed = _run(keys, args)
    if args.json:
        _write_json(args, takes, cells, failed)
    rows = aggregate(cells)
    for half in HALVES:
        half_rows = [r for r in rows if r.half == half]
        if half_rows:
            _print_table(half, half_rows, args.formulations)
            _print_summary(half, half_rows, args.formulations)
    _print_goals(goals(rows))
    for f in failed:
        print(f"FAILED CELL {f.key.recording} {f.key.condition} seed {f.key.seed} {f.key.formulation}: {f.error}")


def _arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--half", choices=(*HALVES, "both"), default="both")
    parser.add_argument("--recordings", nargs="+", choices=[r.name for r in RECORDINGS], default=[])
    parser.add_argument("--conditions", nargs="+", choices=list(CONDITIONS), default=list(CONDITIONS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--formulations", nargs="+", default=["lp-l1", BASELINE])
    parser.add_argument("--frames", type=int, default=0, help="cap on frames per take; 0: full length")
    parser.add_argument("--block", type=int, default=1000, help="frames per accuracy block")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    parser.add_argument("--json", type=Path, help="write every cell here")
    parser.add_argument("--mht-reading", action="store_true", help="read doubtful takes by mht too (LabelingOptions.mht_reading)")
    parser.add_argument("--data", type=Path, default=DATA, help="the shared data folder")
    parser.add_argument("--frame-step", type=int, default=1,
                        help="keep every k-th frame of each take: the takes at 1/k of their frame rates")
    args = parser.parse_args()
    if args.frame_step < 1:
        parser.error(f"--frame-step must be 1 or more, got {args.frame_step}")
    return args


@dataclass(frozen=True)
class _Failed:
    key: CellKey
    error: str


def _attempt(work: Callable[[CellKey], Cell], key: CellKey) -> Cell | _Failed:
    """One cell; an error of the labeler fails that cell, not the whole matrix."""
    try:
        return work(key)
    except Exception as error:  # any labeler error is a finding to list, whatever its type
        return _Failed(key, f"{type(error).__name__}: {error}")


def _run(keys: list[CellKey], args: argparse.Namespace) -> tuple[list[Cell], list[_Failed]]:
    """Every cell, with one progress line per cell on stderr."""
    work = partial(_attempt, partial(run_cell, frames_cap=args.frames, data=args.data, block_frames=args.block,
                                     mht_reading=args.mht_reading, frame_step=args.frame_step))
    done: list[Cell | _Failed] = []
    start = time.perf_counter()
    with Pool(args.jobs) if args.jobs > 1 else nullcontext() as pool:
        for out in pool.imap_unordered(work, keys) if pool else map(work, keys):
            done.append(out)
            k, outcome = out.key, (out.error if isinstance(out, _Failed) else f"{out.accuracy:.2%}, {out.swaps} swaps")
            print(f"[{len(done)}/{len(keys)} {time.perf_counter() - start:6.0f} s] {k.recording} {k.condition} "
                  f"seed {k.seed} {k.formulation}: {outcome}", file=sys.stderr)
    return [c for c in done if isinstance(c, Cell)], [f for f in done if isinstance(f, _Failed)]


def _write_json(args: argparse.Namespace, takes: list[Take], cells: list[Cell], failed: list[_Failed]) -> None:
    settings = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
    document = {
        "settings": settings,
        "takes": [{"recording": t.recording.name, "half": t.recording.half, "start": t.start,
                   "frames": t.frames, "markers": t.truth.n_markers, "dropped": list(t.dropped),
                   "own_gaps": t.own_gaps, "rate": t.truth.rate} for t in takes],
        "cells": [asdict(c) for c in sorted(cells, key=lambda c: astuple(c.key))],
        "failed": [asdict(f) for f in sorted(failed, key=lambda f: astuple(f.key))],
    }
    args.json.write_text(json.dumps(document, indent=1))
    print(f"wrote {len(cells)} cells to {args.json}", file=sys.stderr)


def _print_takes(takes: list[Take], cap: int) -> None:
    print("Takes (start: first frame with the most markers present, unless fixed; markers absent there dropped)")
    print(f"{'recording':18s} {'half':10s} {'lab':24s} {'Hz':>5s} {'start':>5s} {'frames':>6s} {'mk':>3s} {'gaps %':>6s}"
          "  dropped")
    for t in takes:
        frames = min(cap, t.frames) if cap else t.frames
        dropped = ", ".join(t.dropped) or "-"
        if t.recording.exclude:
            dropped += f" (left out: {', '.join(t.recording.exclude)})"
        print(f"{t.recording.name:18s} {t.recording.half:10s} {t.recording.lab:24s} {t.truth.rate:5.0f} {t.start:5d} {frames:6d} "
              f"{t.truth.n_markers:3d} {100 * t.own_gaps:6.1f}  {dropped}")
    print()


def _print_table(half: str, rows: list[Row], formulations: list[str]) -> None:
    print(f"== {half} half ==")
    print(f"{'':18s} {'':9s} {'':>6s} " + " | ".join(f"{f:^53s}" for f in formulations))
    print(f"{'recording':18s} {'condition':9s} {'frames':>6s} " + " | ".join(_COLUMNS for _ in formulations))
    by_key = {(r.recording, r.condition, r.formulation): r for r in rows}
    for rec, cond in dict.fromkeys((r.recording, r.condition) for r in rows):
        cells = [by_key.get((rec, cond, f)) for f in formulations]
        frames = next(r.frames for r in cells if r is not None)
        print(f"{rec:18s} {cond:9s} {frames:6d} " + " | ".join(_figures(r) for r in cells))
    print()


def _figures(r: Row | None) -> str:
    if r is None:
        return f"{'-':>53s}"
    ms, blocks = 1000 * r.seconds_per_frame, r.block_accuracy
    return (f"{100 * r.accuracy:7.2f} {100 * r.known_accuracy:6.2f} {r.swaps:5d} {r.missed:5d} {r.took_ghost:5d} {ms:5.1f} "
            f"{100 * min(blocks):7.2f} {100 * blocks[-1]:6.2f}")


def _print_summary(half: str, rows: list[Row], formulations: list[str]) -> None:
    print(f"Mean accuracy % over the {half} recordings")
    print(f"{'condition':9s} " + " ".join(f"{f:>14s}" for f in formulations))
    for cond in dict.fromkeys(r.condition for r in rows):
        means = [np.mean([r.accuracy for r in rows if r.condition == cond and r.formulation == f] or [np.nan])
                 for f in formulations]
        print(f"{cond:9s} " + " ".join(f"{100 * m:14.2f}" for m in means))
    by_key = {(r.recording, r.condition, r.formulation): r for r in rows}
    for r_f in (f for f in formulations if f != BASELINE):
        pairs = [(r, by_key[(r.recording, r.condition, BASELINE)]) for r in rows
                 if r.formulation == r_f and (r.recording, r.condition, BASELINE) in by_key]
        wins = sum(r.accuracy >= b.accuracy and r.swaps <= b.swaps for r, b in pairs)
        print(f"{r_f} >= {BASELINE} with no more swaps: {wins} / {len(pairs)} rows")
    print()


def _print_goals(checks: list[Goal]) -> None:
    if not checks:
        return
    print("Goals on the validation rows")
    for goal in dict.fromkeys(c.goal for c in checks):
        of_goal = [c for c in checks if c.goal == goal]
        print(f"{goal}: {sum(c.passed for c in of_goal)} / {len(of_goal)} pass")
    for c in checks:
        if not c.passed:
            print(f"  FAIL {c.goal:14s} {c.recording:18s} {c.condition:9s} {c.formulation:12s} {c.detail}")


if __name__ == "__main__":
    main()
