"""Jiang et al. (2008) Table I, swept over observations per frame: extended DP vs LP vs ILP.

3 objects x 20 frames, k observations per frame shared by all objects (``jiang_instance``).
Per size, medians over seeds of the wall time of

    dp-extended (decompose=False): the joint Viterbi, O(M S^2) with S ~ (k+1)^3 joint states,
    lp-l1       (decompose=False): the whole-window LP (column generation when large), rounded,
    ilp         (decompose=False): the 0/1 program by HiGHS branch and bound,

the DP/LP time ratio (medians), whether the LP optimum was integral, and whether LP, ILP and DP
found the same optimum. Extended DP stops where it is refused (max_states) or once a
run takes longer than --budget seconds; for the sizes after that its time is
extrapolated from the last measured rate per transition entry (marked "est.").

    .venv/bin/python bench/extended_dp_vs_lp.py [--seeds 3] [--budget 60] [--sizes 5 8 11 15 20 30 50]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from formulations.errors import FormulationError  # noqa: E402
from formulations.methods.dp_extended import DpExtended  # noqa: E402
from formulations.methods.ilp import Ilp  # noqa: E402
from formulations.methods.lp_l1 import LpL1  # noqa: E402
from formulations.window.build import build_window  # noqa: E402
from service.evaluation.jiang_instance import jiang_instance  # noqa: E402

N_OBJECTS, N_FRAMES = 3, 20


def timed(fn, *args):
    start = time.perf_counter()
    value = fn(*args)
    return value, time.perf_counter() - start


def joint_states(k: int) -> int:
    """Feasible joint states per frame: j of the N objects visible on distinct observations."""
    return sum(math.comb(N_OBJECTS, j) * math.perm(k, j) for j in range(N_OBJECTS + 1))


def transition_entries(k: int) -> int:
    """Entries of all joint transition matrices: source -> 1, M-1 inner steps, M -> sink."""
    s = joint_states(k)
    return (N_FRAMES - 1) * s * s + 2 * s


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--budget", type=float, default=60.0, help="seconds; no DP runs after one takes longer")
    parser.add_argument("--sizes", type=int, nargs="+", default=[5, 8, 11, 15, 20, 30, 50])
    args = parser.parse_args()
    dp, lp, ilp = DpExtended(decompose=False), LpL1(decompose=False), Ilp(decompose=False)
    dp_stopped, rate = "", float("nan")  # why DP stopped; its seconds per transition entry
    print(f"Jiang Table I sweep: {N_OBJECTS} objects x {N_FRAMES} frames, k observations per frame, "
          f"{args.seeds} seeds, DP budget {args.budget:g} s")
    print(f"{'k':>3s} {'states/frame':>12s} {'LP ms':>8s} {'ILP ms':>8s} {'DP s':>12s} {'DP runs':>7s} {'DP/LP':>9s} "
          f"{'LP integral':>11s} {'LP=ILP=DP':>9s} {'ILP status':>12s}")
    for k in args.sizes:
        rows = []
        for seed in range(args.seeds):
            instance = jiang_instance(N_OBJECTS, N_FRAMES, n_observations=k, seed=seed)
            problem = build_window(instance.candidates, instance.weights)[0]
            lp_solution, lp_seconds = timed(lp.solve, problem)
            ilp_solution, ilp_seconds = timed(ilp.solve, problem)
            dp_cost, dp_seconds = np.nan, np.nan
            if not dp_stopped:
                try:
                    dp_solution, dp_seconds = timed(dp.solve, problem)
                    dp_cost = dp_solution.cost
                    rate = dp_seconds / transition_entries(k)
                    if dp_seconds > args.budget:
                        dp_stopped = f"a run took {dp_seconds:.3g} s > {args.budget:g} s at k = {k}"
                except FormulationError as error:
                    dp_stopped = f"refused at k = {k}: {error}"
            costs = [lp_solution.cost, ilp_solution.cost] + ([] if np.isnan(dp_cost) else [dp_cost])
            rows.append({
                "lp": lp_seconds, "ilp": ilp_seconds, "dp": dp_seconds, "integral": lp_solution.integral,
                "agree": lp_solution.integral and max(costs) - min(costs) <= 1e-6, "status": ilp_solution.status,
            })
        lp_ms, ilp_ms = (1000 * np.median([r[key] for r in rows]) for key in ("lp", "ilp"))
        measured = [r["dp"] for r in rows if not np.isnan(r["dp"])]
        dp_s = np.median(measured) if measured else rate * transition_entries(k)
        dp_text = f"{dp_s:.3g}" if measured else f"{dp_s:.3g} est."
        statuses = sorted({r["status"] for r in rows})
        print(f"{k:3d} {joint_states(k):12,d} {lp_ms:8.1f} {ilp_ms:8.1f} {dp_text:>12s} "
              f"{len(measured):>3d}/{len(rows):<3d} {1000 * dp_s / lp_ms:9.3g} "
              f"{sum(r['integral'] for r in rows):>5d}/{len(rows):<5d} {sum(r['agree'] for r in rows):>4d}/{len(rows):<4d} "
              f"{', '.join(statuses):>12s}")
    if dp_stopped:
        print(f"extended DP stopped: {dp_stopped}; later DP times extrapolated at {1e9 * rate:.2f} ns per "
              "transition entry (the last run's rate); without a DP run, LP=ILP=DP compares LP and ILP only")


if __name__ == "__main__":
    main()
