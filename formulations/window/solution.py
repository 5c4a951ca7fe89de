"""What every formulation returns for a window."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class WindowSolution:
    """Integral paths for one window, with the certificate that judges them.

    Attributes:
        path: ``(N, M)`` node chosen for each object in frames 1..M (an occlusion node
            where the object is occluded).
        cost: Objective E of ``path`` (see ``formulations.window.objective``).
        lower_bound: Proven lower bound on the optimum (the LP value for relaxations,
            the optimum itself for exact methods).
        integral: True when the relaxation's optimum was already integral (then ``path``
            is globally optimal).
        n_fractional: Number of fractional variables in the relaxation's optimum.
        n_variables: Number of variables in the models solved.
        status: Solver status ("Optimal", or why not).
        build_seconds, solve_seconds, round_seconds: Where the time went.
        components: How the window was split, e.g. {"viterbi": 38, "coupled": 1}: objects
            solved exactly by Viterbi, and coupled components handed to the solver.
    """

    path: np.ndarray
    cost: float
    lower_bound: float
    integral: bool
    n_fractional: int = 0
    n_variables: int = 0
    status: str = "Optimal"
    build_seconds: float = 0.0
    solve_seconds: float = 0.0
    round_seconds: float = 0.0
    components: dict[str, int] = field(default_factory=dict)

    @property
    def gap(self) -> float:
        """Relative gap (cost - bound) / |cost|: 0 means certified optimal."""
        return max(0.0, self.cost - self.lower_bound) / max(abs(self.cost), 1e-9)
