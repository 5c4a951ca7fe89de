"""The backend contract: minimise c.x subject to row_lower <= A x <= row_upper, bounds."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass
class LinearModel:
    """A linear (or 0/1 mixed-integer) model in column-wise sparse form.

    Attributes:
        cost: ``(n,)`` objective c.
        matrix: ``(m, n)`` constraint matrix A, any scipy sparse format.
        row_lower, row_upper: ``(m,)`` row bounds (``-inf``/``inf`` for one-sided rows).
        col_lower, col_upper: ``(n,)`` column bounds.
        integer: ``(n,)`` bool, True for integer columns; None for a pure LP.
    """

    cost: np.ndarray
    matrix: sp.spmatrix
    row_lower: np.ndarray
    row_upper: np.ndarray
    col_lower: np.ndarray
    col_upper: np.ndarray
    integer: np.ndarray | None = None


# A solve stopped by its time limit: HiGHS's model status text, Clarabel's solver status. Its
# answer is the best found in time, not proven; the labeler says how many windows stopped so.
TIME_LIMIT_STATUSES = ("Time limit reached", "MaxTime")


def stopped_by_time(status: str) -> bool:
    """The status (a formulation may append what it did then) says the time limit stopped the solve."""
    return status.startswith(TIME_LIMIT_STATUSES)


@dataclass
class SolveResult:
    """What a solve returns.

    Attributes:
        status: The solver's model status, e.g. "Optimal", "Time limit reached".
        optimal: True when the solver proved optimality (within its tolerances).
        objective: Objective value of ``x`` (nan when there is no solution).
        x: Column values.
        row_dual: Row duals y with reduced costs c - A^T y (LP only; empty for MIP).
        bound: Best proven lower bound (equals objective for a solved LP).
        seconds: Wall time in the solver.
    """

    status: str
    optimal: bool
    objective: float
    x: np.ndarray
    row_dual: np.ndarray
    bound: float
    seconds: float


class SolverBackend(ABC):
    """Initialise with a model, solve, optionally add columns and solve again warm.

    Options go through the typed setters below (each backend maps them onto its own
    option names), so no caller names a solver-specific option. Unset options keep the
    solver's defaults; a setter holds for every later ``solve``, across ``set_model``.
    """

    @abstractmethod
    def set_timeout(self, seconds: float | None) -> None:
        """Stop each ``solve`` after this many seconds (None: no limit)."""

    @abstractmethod
    def set_relative_gap(self, gap: float) -> None:
        """Stop branch and bound once (incumbent - bound) / |incumbent| <= ``gap``."""

    @abstractmethod
    def set_primal_simplex(self) -> None:
        """Solve LPs by primal simplex.

        Columns added by ``add_columns`` leave the current basis primal feasible, so a
        primal re-solve starts warm where a dual one would not.
        """

    @abstractmethod
    def set_interior_point(self, tolerance: float = 1e-8) -> None:
        """Solve LPs by an interior-point method without crossover, cold each time: the duals
        are central in the optimal dual face rather than a vertex of it (column generation
        then needs far fewer rounds), the primal is not a vertex. ``set_primal_simplex`` undoes it.

        Args:
            tolerance: Relative optimality (duality gap and infeasibility) the iterations
                stop at.
        """

    @abstractmethod
    def set_presolve(self, enabled: bool) -> None:
        """Reduce the model before solving it (the solver's default: it decides), or solve it as given."""

    @abstractmethod
    def set_model(self, model: LinearModel) -> None:
        """Load the model (replacing any previous one)."""

    @property
    @abstractmethod
    def model(self) -> LinearModel:
        """The loaded model with every row and column added since (e.g. to load into another backend)."""

    @abstractmethod
    def add_columns(self, cost: np.ndarray, lower: np.ndarray, upper: np.ndarray, columns: sp.csc_matrix) -> None:
        """Append columns to the loaded model, keeping the current basis for a warm start."""

    @abstractmethod
    def add_rows(self, lower: np.ndarray, upper: np.ndarray) -> None:
        """Append empty rows (no coefficients yet) with these bounds; later columns may use them."""

    @abstractmethod
    def solve(self) -> SolveResult:
        """Solve the loaded model."""
