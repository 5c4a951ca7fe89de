"""``qp-l2``: Jiang's relaxation with a squared-L2 layout term (Sec. II-C: "the L2 norm can
also be used and the relaxation is a quadratic program"), certified against the L1 objective."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import ClassVar

import cvxpy as cp
import numpy as np
import scipy.sparse as sp

from formulations.errors import FormulationError
from formulations.methods.formulation import MAX_INTEGRALITY_TOLERANCE, check_parameters
from formulations.relaxation.certify import Relaxation, round_and_certify
from formulations.relaxation.decomposition import ComponentwiseFormulation
from formulations.relaxation.lp_model import inflow_matrix
from formulations.relaxation.solve_lp import solve_window_lp
from formulations.window.problem import SOURCE, WindowProblem
from formulations.window.solution import WindowSolution

BOUNDS = ("arc-lp", "l1-lp")


@dataclass(frozen=True)
class QpL2(ComponentwiseFormulation):
    """Multi-path flow relaxation with a squared-L2 layout term, solved by Clarabel.

    The QP over arc values xi in [0, 1], with y = H xi (inflow) and p_{n,m} = sum r_v y_v:

        min  c.xi + sum_{(a,b)} mu_ab sum_{m=1}^{M-1} || (p_a,m - p_a,m+1) - (p_b,m - p_b,m+1) ||_2^2
        s.t. one unit out of each source, conservation in frames 1..M, sum_{v in G} y_v <= 1.

    Squared because it keeps the problem a QP, min c.xi + ||L y||^2 with P = L^T L PSD,
    which Clarabel takes directly; the plain norm would be a second-order cone. Its optimum
    y is rounded by Jiang's greedy rule and the paths priced by the L1 objective E.

    The QP value bounds the L2 problem, not min E (v^2 > |v| for |v| > 1). The reported
    bound is an LP relaxation, exact by HiGHS simplex, of a problem whose optimum is <= min E:
      * "arc-lp": the LP with the layout term dropped. mu >= 0, so E(x) >= c.x for every
        feasible integral x, which also lies in the LP polytope: LP <= min c.x <= min E.
      * "l1-lp": lp-l1's LP. At integral x, p+ and p- set to the positive and negative parts
        of each layout difference give an LP point of value E(x): LP <= min E. Tighter,
        but it costs an LP with the layout rows.

    Attributes:
        decompose: Solve independent components apart (Viterbi where exact).
        integrality_tolerance: xi within this of 0 or 1 counts as integral, in (0, 0.5)
            (interior point: zeros come back as ~1e-9).
        bound: Lower bound on the L1 optimum to report: "arc-lp" or "l1-lp".
    """

    name: ClassVar[str] = "qp-l2"
    decompose: bool = True
    integrality_tolerance: float = 1e-5
    bound: str = "arc-lp"

    def __post_init__(self) -> None:
        check_parameters(self, positive=("integrality_tolerance",), flags=("decompose",),
                         below={"integrality_tolerance": MAX_INTEGRALITY_TOLERANCE})
        if self.bound not in BOUNDS:
            raise FormulationError(f"{self.name}: parameter 'bound' must be one of {', '.join(BOUNDS)}, got {self.bound!r}")

    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """Solve the QP, round its y, and certify with the chosen LP bound."""
        if (problem.layout_weight < 0).any():
            raise FormulationError(f"{self.name}: layout weight mu must be >= 0, got {problem.layout_weight.min()!r}")
        start = time.perf_counter()
        xi, qp = self.relax(problem)
        qp_seconds = time.perf_counter() - start
        # cvxpy compiles inside solve(): all but Clarabel's own time counts as building.
        clarabel = (qp.solver_stats.solve_time or 0.0) if qp.solver_stats else 0.0
        no_layout = dataclasses.replace(problem, layout_pairs=problem.layout_pairs[:0], layout_weight=problem.layout_weight[:0])
        lp = solve_window_lp(problem if self.bound == "l1-lp" else no_layout)
        qp_status = "Optimal" if qp.status == cp.OPTIMAL else f"qp {qp.status}"
        relaxation = Relaxation(
            xi=xi, bound=lp.bound, optimal=lp.optimal,
            status=qp_status if lp.status == "Optimal" else f"{qp_status}; bound {lp.status}",
            n_variables=qp.size_metrics.num_scalar_variables + lp.n_variables,
            build_seconds=qp_seconds - clarabel + lp.build_seconds, solve_seconds=clarabel + lp.solve_seconds,
            xi_is_bounding=False,  # the QP's xi: only cost = bound certifies the L1 objective
        )
        return round_and_certify(problem, relaxation, self.integrality_tolerance)

    @staticmethod
    def relax(problem: WindowProblem) -> tuple[np.ndarray, cp.Problem]:
        """Build the QP in cvxpy and solve it with Clarabel.

        Returns:
            xi clipped to [0, 1] (zeros when there is no solution), and the solved problem.
        """
        a = problem.n_arcs
        # y is a variable, not the expression H xi: a layout or conflict row then touches a
        # few nodes instead of every arc into them, and Clarabel's KKT factor stays sparse
        # (about 10x faster on a 15-object window).
        xi, y = cp.Variable(a, nonneg=True), cp.Variable(problem.n_nodes)
        outflow = sp.csr_matrix((np.ones(a), (problem.arc_tail, np.arange(a))), shape=(problem.n_nodes, a))
        inner = (problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames)
        constraints = [
            y == inflow_matrix(problem) @ xi, outflow[problem.node_kind == SOURCE] @ xi == 1,
            y[inner] == outflow[inner] @ xi, xi <= 1,
        ]
        groups = problem.conflict_groups
        if groups.shape[0]:
            constraints.append(groups @ y <= 1)
        objective = problem.arc_cost @ xi
        layout = _layout_operator(problem)
        if layout.shape[0]:
            objective = objective + cp.sum_squares(layout @ y)
        qp = cp.Problem(cp.Minimize(objective), constraints)
        qp.solve(solver="CLARABEL")  # type: ignore[no-untyped-call]  # cvxpy's solve is unannotated
        return (np.zeros(a) if xi.value is None else np.clip(xi.value, 0.0, 1.0)), qp


def _layout_operator(problem: WindowProblem) -> sp.csr_matrix:
    """``(L, V)``: sqrt(mu_ab) ((p_a,m - p_a,m+1) - (p_b,m - p_b,m+1))_l as a map of y, rows (l, pair, m)."""
    n, m, pairs = problem.n_objects, problem.n_frames, problem.layout_pairs
    if len(pairs) == 0 or m < 2:
        return sp.csr_matrix((0, problem.n_nodes))
    inner = np.flatnonzero((problem.node_frame >= 1) & (problem.node_frame <= m))
    block = problem.node_object[inner] * m + problem.node_frame[inner] - 1
    step = np.tile(np.arange(m - 1), len(pairs))
    a, b = np.repeat(pairs[:, 0], m - 1) * m + step, np.repeat(pairs[:, 1], m - 1) * m + step
    root = np.repeat(np.sqrt(problem.layout_weight), m - 1)
    difference = sp.csr_matrix(
        (np.column_stack([root, -root, -root, root]).ravel(),
         (np.repeat(np.arange(len(step)), 4), np.column_stack([a, a + 1, b, b + 1]).ravel())),
        shape=(len(step), n * m),
    )
    locate = [sp.csr_matrix((problem.node_location[inner, l], (block, inner)), shape=(n * m, problem.n_nodes))
              for l in range(problem.dimension)]
    return sp.vstack([difference @ p for p in locate]).tocsr()
