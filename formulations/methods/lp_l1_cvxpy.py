"""``lp-l1-cvxpy``: the same LP written plainly in cvxpy — the reference ``lp-l1`` is tested against.

Built independently of ``formulations.relaxation.lp_model`` (conflict groups straight from the
resource columns, locations as explicit sums), so agreement of the two optima checks
the fast sparse build rather than repeating it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import cvxpy as cp
import numpy as np
import scipy.sparse as sp

from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation
from formulations.relaxation.certify import Relaxation, round_and_certify
from formulations.solvers.quiet import stdout_to_stderr
from formulations.window.problem import SOURCE, WindowProblem
from formulations.window.solution import WindowSolution


@dataclass(frozen=True)
class LpL1Cvxpy(Formulation):
    """Jiang's LP relaxation (Sec. II-D) modelled in cvxpy, solved by HiGHS through cvxpy.

    Attributes:
        solver: cvxpy solver name.
    """

    name: ClassVar[str] = "lp-l1-cvxpy"
    solver: str = "HIGHS"

    def __post_init__(self) -> None:
        # A typo must fail when the formulation is chosen, not inside the first window.
        installed = cp.installed_solvers()  # type: ignore[no-untyped-call]  # cvxpy is unannotated
        if self.solver not in installed:
            raise FormulationError(
                f"{self.name}: parameter 'solver' must be an installed cvxpy solver ({', '.join(installed)}), "
                f"got {self.solver!r}"
            )

    def solve(self, problem: WindowProblem) -> WindowSolution:
        start = time.perf_counter()
        xi, lp = self.model(problem)
        build = time.perf_counter() - start
        with stdout_to_stderr():  # cvxpy's HiGHS prints a banner on construction
            lp.solve(solver=self.solver)  # type: ignore[no-untyped-call]  # cvxpy is unannotated
        optimal = lp.status == cp.OPTIMAL
        relaxation = Relaxation(
            xi=np.zeros(problem.n_arcs) if xi.value is None else np.clip(np.asarray(xi.value, dtype=float), 0.0, 1.0),
            bound=float(lp.value) if optimal else -np.inf, optimal=optimal, status=lp.status,
            n_variables=lp.size_metrics.num_scalar_variables, build_seconds=build,
            solve_seconds=time.perf_counter() - start - build,
        )
        return round_and_certify(problem, relaxation)

    @staticmethod
    def model(problem: WindowProblem) -> tuple[cp.Variable, cp.Problem]:
        """The cvxpy problem and its arc variable."""
        a, v = problem.n_arcs, problem.n_nodes
        xi = cp.Variable(a, nonneg=True)
        into = sp.coo_matrix((np.ones(a), (problem.arc_head, np.arange(a))), shape=(v, a)).tocsr()
        out = sp.coo_matrix((np.ones(a), (problem.arc_tail, np.arange(a))), shape=(v, a)).tocsr()
        y = into @ xi
        inner = (problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames)
        constraints = [out[problem.node_kind == SOURCE] @ xi == 1, y[inner] == (out @ xi)[inner], xi <= 1]
        groups = _contested_resources(problem)
        if groups.shape[0]:
            constraints.append(groups @ y <= 1)
        objective = problem.arc_cost @ xi
        if len(problem.layout_pairs) and problem.n_frames > 1:
            term, extra = _layout_term(problem, y)
            objective, constraints = objective + term, constraints + extra
        return xi, cp.Problem(cp.Minimize(objective), constraints)


def _contested_resources(problem: WindowProblem) -> sp.csr_matrix:
    """(resources used by two or more objects) x nodes, from the (node, resource) pairs."""
    usage = problem.resources.tocoo()
    pairs = np.unique(np.column_stack([usage.col, problem.node_object[usage.row]]), axis=0)
    contested = np.flatnonzero(np.bincount(pairs[:, 0], minlength=problem.resources.shape[1]) > 1)
    return problem.resources.T.tocsr()[contested]


def _layout_term(problem: WindowProblem, y: cp.Expression) -> tuple[cp.Expression, list[cp.Constraint]]:
    """mu sum ||(p_a,m - p_a,m+1) - (p_b,m - p_b,m+1)||_1 with p = sum r y, via p+ and p-."""
    n, m, d = problem.n_objects, problem.n_frames, problem.dimension
    inner = np.flatnonzero((problem.node_frame >= 1) & (problem.node_frame <= m))
    block = problem.node_object[inner] * m + problem.node_frame[inner] - 1
    select = sp.coo_matrix((np.ones(len(inner)), (block, inner)), shape=(n * m, problem.n_nodes)).tocsr()
    p = [cp.reshape(select @ cp.multiply(problem.node_location[:, l], y), (n, m), order="C") for l in range(d)]
    a, b = problem.layout_pairs[:, 0], problem.layout_pairs[:, 1]
    plus = cp.Variable((len(a), d * (m - 1)), nonneg=True)
    minus = cp.Variable((len(a), d * (m - 1)), nonneg=True)
    change = cp.hstack([(p[l][a, :-1] - p[l][a, 1:]) - (p[l][b, :-1] - p[l][b, 1:]) for l in range(d)])
    term = cp.sum(cp.multiply(problem.layout_weight[:, None], plus + minus))
    return term, [plus - minus == change]
