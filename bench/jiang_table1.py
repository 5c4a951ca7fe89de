"""Jiang et al. (2008) Table I instance: 3 objects, 20 frames, 50 observations per frame,
every observation a candidate of every object (the paper: 20 s LP, 18,800 s extended DP).

Prints medians over seeds x repeats of: network construction, LP build, solve, round, for
lp-l1 on the whole window (column generation), lp-l1 without column generation, the
default lp-l1 (decomposed, Viterbi where exact), and the same LP through cvxpy + HiGHS.

    .venv/bin/python bench/jiang_table1.py [--seeds 5] [--repeats 3]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cvxpy as cp
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from formulations.methods.lp_l1 import LpL1  # noqa: E402
from formulations.methods.lp_l1_cvxpy import LpL1Cvxpy  # noqa: E402
from formulations.window.build import build_window  # noqa: E402
from service.evaluation.jiang_instance import jiang_instance  # noqa: E402


def timed(fn, *args):
    start = time.perf_counter()
    value = fn(*args)
    return value, time.perf_counter() - start


def run_direct(problem, formulation):
    solution, total = timed(lambda: formulation.solve(problem))
    return {"build": solution.build_seconds, "solve": solution.solve_seconds, "round": solution.round_seconds,
            "total": total, "integral": solution.integral, "bound": solution.lower_bound, "columns": solution.n_variables}


def run_cvxpy(problem):
    (xi, lp), build = timed(lambda: LpL1Cvxpy.model(problem))
    _, compile_ = timed(lambda: lp.get_problem_data(cp.HIGHS))
    _, solve = timed(lambda: lp.solve(solver=cp.HIGHS))
    return {"build": build + compile_, "solve": solve, "round": 0.0, "total": build + compile_ + solve,
            "integral": None, "bound": lp.value, "columns": xi.size}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    methods = {
        "lp-l1 whole window (pricing)": lambda p: run_direct(p, LpL1(decompose=False)),
        "lp-l1 whole window, all columns": lambda p: run_direct(p, LpL1(decompose=False, pricing_min_arcs=10**9)),
        "lp-l1 default (decomposed)": lambda p: run_direct(p, LpL1()),
        "cvxpy + HiGHS, same LP": run_cvxpy,
    }
    rows = {name: [] for name in methods}
    networks, bounds = [], []
    for seed in range(args.seeds):
        instance = jiang_instance(seed=seed)
        for _ in range(args.repeats):
            (problem, _), seconds = timed(build_window, instance.candidates, instance.weights)
            networks.append(seconds)
        per_seed = {}
        for name, method in methods.items():
            repeats = 1 if name.startswith("cvxpy") or "all columns" in name else args.repeats
            for _ in range(repeats):
                result = method(problem)
                rows[name].append(result)
            per_seed[name] = result["bound"]
        bounds.append(max(per_seed.values()) - min(per_seed.values()))
    print(f"Jiang Table I instance: 3 objects x 20 frames x 50 observations, {problem.n_arcs} arcs, "
          f"{problem.n_nodes} nodes, {problem.conflict_groups.shape[0]} conflict groups")
    print(f"network (candidates -> WindowProblem): median {1000 * np.median(networks):.1f} ms")
    print(f"largest disagreement of LP optima between methods: {max(bounds):.2e}")
    header = (f"{'method':34s} {'runs':>4s} {'build ms':>9s} {'solve ms':>9s} {'round ms':>9s} {'total ms':>9s} "
              f"{'columns':>8s} {'integral':>8s}")
    print(header)
    for name, results in rows.items():
        med = {k: np.median([r[k] for r in results]) for k in ("build", "solve", "round", "total", "columns")}
        integral = [r["integral"] for r in results if r["integral"] is not None]
        frac = f"{np.mean(integral):.0%}" if integral else "-"
        print(f"{name:34s} {len(results):4d} {1000 * med['build']:9.1f} {1000 * med['solve']:9.1f} "
              f"{1000 * med['round']:9.1f} {1000 * med['total']:9.1f} {med['columns']:8.0f} {frac:>8s}")
    # the same full arc LP both ways (pricing builds only a master of paths)
    direct = np.median([r["build"] for r in rows["lp-l1 whole window, all columns"]])
    via_cvxpy = np.median([r["build"] for r in rows["cvxpy + HiGHS, same LP"]])
    whole = np.median([r["total"] for r in rows["lp-l1 whole window (pricing)"]])
    cvx_total = np.median([r["total"] for r in rows["cvxpy + HiGHS, same LP"]])
    print(f"build of the full LP: direct sparse {1000 * direct:.1f} ms vs cvxpy {1000 * via_cvxpy:.0f} ms "
          f"-> {via_cvxpy / direct:.0f}x")
    print(f"build+solve+round: lp-l1 whole window {1000 * whole:.0f} ms vs cvxpy {1000 * cvx_total:.0f} ms "
          f"-> {cvx_total / whole:.0f}x")


if __name__ == "__main__":
    main()
