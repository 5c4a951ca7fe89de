"""``lp-l1``: Jiang's LP relaxation with the L1 layout term, rounded and certified."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from formulations.methods.formulation import (
    MAX_BRANCHING,
    MAX_INTEGRALITY_TOLERANCE,
    TABLE_BRANCHING,
    check_parameters,
)
from formulations.methods.repair import k_best_repair
from formulations.relaxation.certify import INTEGRALITY_TOLERANCE, round_and_certify
from formulations.relaxation.decomposition import ComponentwiseFormulation
from formulations.relaxation.pricing import PRICING_MIN_ARCS, PRICING_SUCCESSORS
from formulations.relaxation.solve_lp import solve_window_lp
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution


@dataclass(frozen=True)
class LpL1(ComponentwiseFormulation):
    """The LP relaxation of multi-path flow with conflict groups (Jiang et al. 2008, II-D).

    Solved with HiGHS dual simplex; a fractional optimum is rounded greedily (II-D) and
    every window carries its certificate: LP bound, cost of the rounded paths, gap.

    Attributes:
        decompose: Solve independent components apart (Viterbi where exact).
        integrality_tolerance: xi within this of 0 or 1 counts as integral, in (0, 0.5).
        pricing_min_arcs: Use column generation when a component has more arcs.
        pricing_successors: Cheapest out-arcs per node in the first restricted LP.
        time_limit: Seconds per LP solve (None: no limit).
        repair: I = J of the k-best repair (``formulations.methods.repair``) run on a
            component whose LP optimum was fractional; 0 turns the repair off; at most 100 (code: 10^4).
    """

    name: ClassVar[str] = "lp-l1"
    table_limits: ClassVar[dict[str, float]] = {"repair": TABLE_BRANCHING}
    decompose: bool = True
    integrality_tolerance: float = INTEGRALITY_TOLERANCE
    pricing_min_arcs: int = PRICING_MIN_ARCS
    pricing_successors: int = PRICING_SUCCESSORS
    time_limit: float | None = None
    repair: int = 10

    def __post_init__(self) -> None:
        check_parameters(self, positive=("integrality_tolerance", "pricing_successors"),
                         non_negative=("pricing_min_arcs", "repair"), optional_positive=("time_limit",),
                         flags=("decompose",), integers=("pricing_min_arcs", "pricing_successors", "repair"),
                         at_most={"repair": MAX_BRANCHING}, below={"integrality_tolerance": MAX_INTEGRALITY_TOLERANCE})

    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """Build, solve, round and certify one LP over the whole (sub-)window; repair if fractional."""
        relaxation = solve_window_lp(problem, self.time_limit, self.pricing_min_arcs, self.pricing_successors)
        rounded = round_and_certify(problem, relaxation, self.integrality_tolerance)
        if rounded.integral or self.repair == 0 or not relaxation.optimal:
            return rounded
        return k_best_repair(problem, rounded, self.repair)
