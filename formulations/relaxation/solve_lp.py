"""Solve the window LP of a (sub-)window: the relaxation behind lp-l1, ilp's LP-first
step and qp-l2's bound.

The LP (``window_lp``) is solved by HiGHS, with all columns on a small window. Once the
window has more than ``pricing_min_arcs`` arcs it is solved by column generation: over
whole paths (``path_lp``) when it has no layout term, else over arcs
(``solve_with_pricing``). Its optimal value is a proven lower bound on min E, since
every feasible set of paths is an integral point of the LP with value E.

Path pricing wins where a window is large and converges in few rounds (03_rolling: 87-106k
arcs, under 80 rounds, under 14 since its duals come from Clarabel; the arc LP took the take
31 -> 104 s), and loses where noise leaves
many near-equal paths and it needs many (Vicon's 51 markers at 4 mm: 12-34k arcs, 100-190
rounds, each window 5-40x slower than the arc LP). It therefore gets one round per
``ARCS_PER_ROUND`` arcs (at least ``MIN_ROUNDS``), about what the arc LP would cost, and
the window is solved as an arc LP with all its columns if it has not converged by then.
"""

from __future__ import annotations

import time

import numpy as np

from formulations.relaxation.certify import Relaxation
from formulations.relaxation.lp_model import window_lp
from formulations.relaxation.path_lp import STALLED, solve_path_lp
from formulations.relaxation.pricing import PRICING_MIN_ARCS, PRICING_SUCCESSORS, initial_columns, solve_with_pricing
from formulations.solvers import create_backend
from formulations.window.problem import WindowProblem

# Chosen on the two takes above (03_rolling 31.0 -> 31.7 s, Vicon at 4 mm 6x faster); over the
# seed-0 accuracy matrix's 85 rows the labels are the same and the median time per frame 1.02x.
# Since the duals come from Clarabel 03_rolling's windows converge in 13 rounds at most (median
# 5), and racing's window LPs take about as long at 1000 or 3000 (2.6-3.4 s, noise); at 3000
# the Vicon 4 mm matrix row falls back after 10 rounds, 160 -> 85 s; over the seed-0 matrix's
# 85 rows the labels are the same and the summed s/frame 1.38 -> 1.12 (one run each, two jobs).
ARCS_PER_ROUND = 3000
MIN_ROUNDS = 10


def solve_window_lp(
    problem: WindowProblem, time_limit: float | None = None, pricing_min_arcs: int = PRICING_MIN_ARCS,
    pricing_successors: int = PRICING_SUCCESSORS,
) -> Relaxation:
    """The LP optimum xi of a window and its value as the bound (-inf unless proven optimal).

    Args:
        problem: The (sub-)window.
        time_limit: Seconds per LP solve (None: no limit).
        pricing_min_arcs: Use column generation when the window has more arcs.
        pricing_successors: Cheapest out-arcs per node in the first restricted arc LP
            (windows with a layout term).
    """
    start = time.perf_counter()
    large, layout = problem.n_arcs > pricing_min_arcs, bool(np.any(problem.layout_weight > 0))
    if large and not layout:
        rounds = max(MIN_ROUNDS, problem.n_arcs // ARCS_PER_ROUND)
        result, n_paths = solve_path_lp(problem, time_limit, rounds)
        if result.status != STALLED:
            return Relaxation(
                xi=result.x, bound=result.bound, optimal=result.optimal,  # L(pi) is proven in any round
                status=result.status, n_variables=n_paths, build_seconds=0.0,
                solve_seconds=time.perf_counter() - start,
            )
    building = time.perf_counter()
    model = window_lp(problem)
    build = time.perf_counter() - building  # a stalled path LP's time counts as solving
    backend = create_backend("highs")
    backend.set_timeout(time_limit)
    if large and layout:
        result, _ = solve_with_pricing(model, backend, initial_columns(problem, len(model.cost), pricing_successors))
    else:
        # Presolve finds little to remove in a window's flow rows and costs more than it saves:
        # over the arc LPs of five labelings (docs/how-a-window-is-solved.md, "lp-l1") the
        # simplex took 0.66-0.98 of the time without it, every solution the same.
        backend.set_presolve(False)
        backend.set_model(model)
        result = backend.solve()
    return Relaxation(
        xi=result.x[: problem.n_arcs] if len(result.x) else np.zeros(problem.n_arcs),
        bound=result.bound if result.optimal else -np.inf, optimal=result.optimal, status=result.status,
        n_variables=len(model.cost), build_seconds=build, solve_seconds=time.perf_counter() - start - build,
    )
