"""``ilp``: the window's 0/1 program solved exactly by branch and bound (Jiang Sec. II-D, IV-A4).

The model is ``window_lp(problem, integer=True)``: the LP of ``formulations.relaxation.lp_model``
with every arc variable restricted to xi_a in {0, 1} (the layout columns p+, p- stay
continuous; at an integral xi they equal the L1 terms exactly). With xi integral the
program *is* the tracking problem

    min_paths  sum_{arcs on paths} c_a + sum_{(a, b)} mu_ab sum_m ||Δ(p_a - p_b)_m||_1
    s.t.       at most one path through each conflict group,

so HiGHS' branch and bound returns the global optimum together with a dual bound
``bound <= optimum``; the run stops once (cost - bound) / |cost| <= ``mip_gap`` or at
the time limit, when the best incumbent is returned with its gap.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from formulations.methods.formulation import check_parameters
from formulations.relaxation.certify import Relaxation, round_and_certify
from formulations.relaxation.decomposition import ComponentwiseFormulation
from formulations.relaxation.lp_model import window_lp
from formulations.relaxation.solve_lp import solve_window_lp
from formulations.solvers import create_backend
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution

# HiGHS' incumbent is integral up to its feasibility tolerance (1e-6): any xi counts as
# integral (no xi has min(xi, 1 - xi) > 0.5), the proof is branch and bound's own.
INCUMBENT_INTEGRALITY = 0.5


@dataclass(frozen=True)
class Ilp(ComponentwiseFormulation):
    """Jiang's 0/1 program solved to proven optimality by HiGHS branch and bound.

    ``integral`` is True only when HiGHS proves the incumbent optimal (within
    ``mip_gap``); ``lower_bound`` is the MIP dual bound, so ``WindowSolution.gap`` is the
    remaining MIP gap when the time limit stops the search.

    Attributes:
        time_limit: Seconds per MIP solve (per coupled component when decomposing; None:
            no limit). On expiry the best incumbent is returned, or the all-occlusion
            paths if there is none.
        mip_gap: Relative gap (cost - bound) / |cost| at which HiGHS stops.
        decompose: Solve independent components apart (Viterbi where exact).
        lp_first: Solve the LP relaxation first and skip branch and bound when its
            optimum is integral (it is then the global optimum: Jiang's observation that
            the LP almost always is, which makes this much faster).
    """

    name: ClassVar[str] = "ilp"
    time_limit: float | None = 60.0
    mip_gap: float = 1e-6
    decompose: bool = True
    lp_first: bool = True

    def __post_init__(self) -> None:
        check_parameters(self, non_negative=("mip_gap",), optional_positive=("time_limit",), flags=("decompose", "lp_first"))

    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """The LP's optimum if integral, else one 0/1 program over the whole (sub-)window."""
        if self.lp_first:
            relaxed = round_and_certify(problem, solve_window_lp(problem, self.time_limit))
            if relaxed.integral:
                relaxed.status = "Optimal (LP relaxation integral)"
                return relaxed
        return round_and_certify(problem, self._branch_and_bound(problem), INCUMBENT_INTEGRALITY)

    def _branch_and_bound(self, problem: WindowProblem) -> Relaxation:
        """The 0/1 program's incumbent as xi, with the MIP dual bound."""
        start = time.perf_counter()
        model = window_lp(problem, integer=True)
        build = time.perf_counter() - start
        backend = create_backend("highs")
        backend.set_timeout(self.time_limit)
        backend.set_relative_gap(self.mip_gap)
        backend.set_model(model)
        result = backend.solve()
        has_incumbent = len(result.x) > 0
        return Relaxation(
            # No incumbent: zero arc values round to the all-occlusion paths (ties go to the
            # occlusion node), which conflict with nothing and so are always feasible.
            xi=result.x[: problem.n_arcs] if has_incumbent else np.zeros(problem.n_arcs),
            bound=-np.inf if np.isnan(result.bound) else float(result.bound), optimal=result.optimal,
            status=result.status if has_incumbent else f"{result.status}; no incumbent, all-occlusion paths returned",
            n_variables=len(model.cost), build_seconds=build, solve_seconds=time.perf_counter() - start - build,
        )
