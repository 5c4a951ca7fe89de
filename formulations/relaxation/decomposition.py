"""Solve a window component by component (see ``formulations.relaxation.components``).

An object coupled to nobody gets its Viterbi path: exact, no LP. A coupled component
whose objects' Viterbi paths happen not to collide (and that has no layout term) is
also exact: dropping the conflict rows relaxes the problem, and the relaxation's
integral optimum is feasible. Only the remaining components reach ``solve_coupled``.
"""

from __future__ import annotations

import time
from abc import abstractmethod
from collections import Counter
from collections.abc import Callable

import numpy as np

from formulations.methods.formulation import Formulation
from formulations.relaxation.components import coupled_components, restrict
from formulations.relaxation.viterbi import shortest_paths
from formulations.window.objective import conflicts, path_cost
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution


def solve_decomposed(
    problem: WindowProblem, solve_coupled: Callable[[WindowProblem], WindowSolution]
) -> WindowSolution:
    """Viterbi where exact, ``solve_coupled`` on each remaining component."""
    start = time.perf_counter()
    path, path_costs = shortest_paths(problem)
    label = coupled_components(problem)
    needs_solver = np.zeros(label.max() + 1 if len(label) else 0, dtype=bool)
    colliding = np.unique(problem.node_object[problem.conflict_groups[conflicts(problem, path)].indices])
    needs_solver[label[colliding]] = True
    needs_solver[label[problem.layout_pairs[problem.layout_weight > 0].ravel()]] = True
    bound = float(path_costs[~needs_solver[label]].sum())
    counts: Counter[str] = Counter(viterbi=int((~needs_solver[label]).sum()))
    parts: list[WindowSolution] = []
    for component in np.flatnonzero(needs_solver):
        objects = np.flatnonzero(label == component)
        sub, nodes = restrict(problem, objects)
        part = solve_coupled(sub)
        path[objects] = nodes[part.path]
        bound += part.lower_bound
        parts.append(part)
        counts["coupled"] += 1
    solve_seconds = time.perf_counter() - start - sum(p.build_seconds + p.round_seconds for p in parts)
    return WindowSolution(
        path=path, cost=path_cost(problem, path), lower_bound=bound,
        integral=all(p.integral for p in parts), n_fractional=sum(p.n_fractional for p in parts),
        n_variables=sum(p.n_variables for p in parts),
        status=next((p.status for p in parts if p.status != "Optimal"), "Optimal"),
        build_seconds=sum(p.build_seconds for p in parts), solve_seconds=solve_seconds,
        round_seconds=sum(p.round_seconds for p in parts), components=dict(counts),
    )


class ComponentwiseFormulation(Formulation):
    """A formulation that solves each coupled component with ``solve_coupled``.

    Subclasses have a ``decompose`` parameter; when it is False the whole window goes to
    ``solve_coupled`` at once.
    """

    decompose: bool

    def solve(self, problem: WindowProblem) -> WindowSolution:
        if self.decompose:
            return solve_decomposed(problem, self.solve_coupled)
        return self.solve_coupled(problem)

    @abstractmethod
    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """Solve one (sub-)window as a whole."""
