"""Round a relaxation's optimum to integral paths and certify them: how every relaxed
formulation ends (Jiang, Fels & Little 2008, Sec. II-D).

A relaxation hands over arc values xi in [0, 1] and a proven lower bound L <= min E
(-inf when its solver proved none). The node values

    y_v = sum_{a: head(a) = v} xi_a                   (y = H xi, the inflow)

are rounded by Jiang's greedy rule (``round_greedy``), which is always feasible, and the
paths priced by the window objective: cost = E(paths) >= min E >= L. Then

  * when xi is optimal for the problem whose value is L (the LP, or the 0/1 program
    itself) and integral (every xi_a within the tolerance of 0 or 1), the rounding
    returns xi's own paths, cost = L, and they are globally optimal: ``integral``;
  * when xi solves another problem (qp-l2's QP) its integrality proves nothing; the
    paths are certified only when cost - L <= 1e-9 max(1, |cost|);
  * otherwise the paths are feasible and gap = (cost - L) / |cost| bounds how far
    from the optimum they can be (``WindowSolution.gap``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from formulations.relaxation.rounding import round_greedy
from formulations.window.objective import path_cost
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution

CERTIFIED = 1e-9  # relative cost - bound under which rounded paths count as proven optimal
INTEGRALITY_TOLERANCE = 1e-6  # default: xi_a within this of 0 or 1 counts as integral


@dataclass(frozen=True)
class Relaxation:
    """A relaxation's solution, before rounding.

    Attributes:
        xi: ``(A,)`` arc values in [0, 1] (zeros when the solver returned none: they round
            to the all-occlusion paths).
        bound: Proven lower bound L on min E (-inf when none was proven).
        optimal: The solver proved its optimum (for qp-l2: the optimum of the LP giving L).
        status: Solver status ("Optimal", or why not).
        n_variables: Number of variables in the models solved.
        build_seconds, solve_seconds: Where the time went.
        xi_is_bounding: True when L is the optimal value of the problem xi solves, so an
            integral xi is an optimal path set; False when xi comes from another problem.
    """

    xi: np.ndarray
    bound: float
    optimal: bool
    status: str
    n_variables: int
    build_seconds: float
    solve_seconds: float
    xi_is_bounding: bool = True


def round_and_certify(
    problem: WindowProblem, relaxation: Relaxation, integrality_tolerance: float = INTEGRALITY_TOLERANCE
) -> WindowSolution:
    """Greedy-round ``relaxation.xi`` and attach the certificate (see the module docstring).

    Args:
        problem: The (sub-)window the relaxation was posed on.
        relaxation: Its solution and bound.
        integrality_tolerance: xi_a within this of 0 or 1 counts as integral.
    """
    start = time.perf_counter()
    xi = relaxation.xi
    n_fractional = int(np.sum(np.minimum(xi, 1.0 - xi) > integrality_tolerance))
    # y = H xi (``lp_model.inflow_matrix``): each node's in-arcs summed in arc order, as the
    # sparse product does, without building H
    path = round_greedy(problem, np.bincount(problem.arc_head, weights=xi, minlength=problem.n_nodes))
    cost = path_cost(problem, path)
    meets_bound = cost - relaxation.bound <= CERTIFIED * max(1.0, abs(cost))
    proven = n_fractional == 0 if relaxation.xi_is_bounding else meets_bound
    return WindowSolution(
        path=path, cost=cost, lower_bound=relaxation.bound, integral=relaxation.optimal and proven,
        n_fractional=n_fractional, n_variables=relaxation.n_variables, status=relaxation.status,
        build_seconds=relaxation.build_seconds, solve_seconds=relaxation.solve_seconds,
        round_seconds=time.perf_counter() - start,
    )
