"""Clarabel as an interior-point LP backend: central duals for column generation.

Path pricing (``relaxation.path_lp``) wants each restricted master's duals central in its
optimal dual face, which an interior point without crossover gives. HiGHS' IPX has a fixed
cost per solve that dominates on masters of a few hundred rows and columns, solved tens of
times per window; Clarabel solves the same masters several times faster, to the same
optima (``bench/path_lp.py``, every path-LP window of a first pass, medians of 3:
03_rolling 16.98 -> 3.73 s, wheelchair racing 8.60 -> 3.32 s, tennis 0.48 -> 0.34 s, every
objective the same), and its duals price in fewer columns (master solves 1,533 -> 524 on
03_rolling). It has no simplex and no warm start: a vertex is HiGHS' job
(``set_primal_simplex`` refuses), and each ``solve`` starts cold from the loaded model.

Clarabel solves min c.x s.t. A x + s = b, s in K; a row l <= a.x <= u is a zero-cone row
when l = u, else a non-negative row u - a.x (u finite) and one a.x - l (l finite); column
bounds likewise. With z its cone duals, c + A^T z = 0 at the optimum, so the row duals in
``SolveResult``'s convention (reduced costs c - A^T y) are y = -z.
"""

from __future__ import annotations

import time
from dataclasses import replace

import clarabel
import numpy as np
import scipy.sparse as sp

from formulations.solvers.base import LinearModel, SolverBackend, SolveResult

_SOLVED = (clarabel.SolverStatus.Solved, clarabel.SolverStatus.AlmostSolved)


class ClarabelBackend(SolverBackend):
    """Interior-point LPs by Clarabel, rebuilt from the model at every solve (module doc)."""

    def __init__(self) -> None:
        self._settings = clarabel.DefaultSettings()
        self._settings.verbose = False
        # The duals only price columns; the optimum reported is a simplex vertex (module doc).
        # Without refining each KKT solve the masters of 03_rolling's first pass took 2.5 ->
        # 2.1 s, the same rounds and columns, every arc value the same to 1e-8; the seed-0
        # accuracy matrix's 85 rows and the real takes keep their labels.
        self._settings.iterative_refinement_enable = False
        self._model: LinearModel | None = None

    @property
    def model(self) -> LinearModel:
        """The loaded model with every row and column added since."""
        if self._model is None:
            raise ValueError("no model loaded")
        return self._model

    def set_timeout(self, seconds: float | None) -> None:
        self._settings.time_limit = float(seconds) if seconds else float("inf")

    def set_relative_gap(self, gap: float) -> None:
        raise NotImplementedError("the Clarabel backend solves no MIP; use 'highs'")

    def set_primal_simplex(self) -> None:
        raise NotImplementedError("Clarabel has no simplex; load the model into 'highs' for a vertex")

    def set_interior_point(self, tolerance: float = 1e-8) -> None:
        self._settings.tol_gap_abs = self._settings.tol_gap_rel = float(tolerance)
        self._settings.tol_feas = float(tolerance)

    def set_presolve(self, enabled: bool) -> None:
        self._settings.presolve_enable = bool(enabled)

    def set_model(self, model: LinearModel) -> None:
        if model.integer is not None and np.any(model.integer):
            raise ValueError("the Clarabel backend solves no MIP; use 'highs'")
        self._model = replace(model, matrix=sp.csc_matrix(model.matrix))

    def add_columns(self, cost: np.ndarray, lower: np.ndarray, upper: np.ndarray, columns: sp.csc_matrix) -> None:
        m = self.model
        self._model = replace(m, cost=np.r_[m.cost, cost], col_lower=np.r_[m.col_lower, lower],
                              col_upper=np.r_[m.col_upper, upper], matrix=sp.hstack([m.matrix, columns], format="csc"))

    def add_rows(self, lower: np.ndarray, upper: np.ndarray) -> None:
        m = self.model
        matrix = sp.vstack([m.matrix, sp.csc_matrix((len(lower), m.matrix.shape[1]))], format="csc")
        self._model = replace(m, matrix=matrix, row_lower=np.r_[m.row_lower, lower], row_upper=np.r_[m.row_upper, upper])

    def solve(self) -> SolveResult:
        start = time.perf_counter()
        m = self.model
        k = m.matrix.shape[1]
        lower, upper = np.r_[m.row_lower, m.col_lower], np.r_[m.row_upper, m.col_upper]
        equal = lower == upper
        below, above = ~equal & np.isfinite(upper), ~equal & np.isfinite(lower)
        a = _cone_rows(m.matrix, equal, below, above)
        b = np.r_[upper[equal], upper[below], -lower[above]]
        cones = [clarabel.ZeroConeT(int(equal.sum())), clarabel.NonnegativeConeT(int(below.sum() + above.sum()))]
        solution = clarabel.DefaultSolver(sp.csc_matrix((k, k)), np.asarray(m.cost, float), a, b, cones,
                                          self._settings).solve()
        optimal = solution.status in _SOLVED
        z = np.asarray(solution.z)
        n_equal, n_below = int(equal.sum()), int(below.sum())
        dual = np.zeros(len(lower))  # y = -z per row: a row's upper side minus its lower side
        dual[equal] = -z[:n_equal]
        dual[below] -= z[n_equal:n_equal + n_below]
        dual[above] += z[n_equal + n_below:]
        objective = float(solution.obj_val) if optimal else float("nan")
        return SolveResult(
            status=str(solution.status), optimal=optimal, objective=objective,
            x=np.asarray(solution.x) if optimal else np.zeros(0), row_dual=dual[:len(m.row_lower)] if optimal else np.zeros(0),
            bound=objective, seconds=time.perf_counter() - start,
        )


def _cone_rows(matrix: sp.spmatrix, equal: np.ndarray, below: np.ndarray, above: np.ndarray) -> sp.csc_matrix:
    """The cone rows of ``[matrix; I]`` (a row per column bound after the model's rows): the
    ``equal`` rows, then the ``below`` rows, then the ``above`` rows negated; built from the
    entries at once (stacking and slicing sparse matrices cost as much as the solve)."""
    entries = sp.coo_matrix(matrix)
    k = entries.shape[1]
    row = np.r_[entries.row, entries.shape[0] + np.arange(k)]
    col, value = np.r_[entries.col, np.arange(k)], np.r_[entries.data, np.ones(k)]
    n_equal, n_below = int(equal.sum()), int(below.sum())
    parts = [(equal, np.cumsum(equal) - 1, 1.0), (below, n_equal + np.cumsum(below) - 1, 1.0),
             (above, n_equal + n_below + np.cumsum(above) - 1, -1.0)]
    picked = [(at[row[side[row]]], col[side[row]], sign * value[side[row]]) for side, at, sign in parts]
    rows, cols, values = (np.concatenate(part) for part in zip(*picked))
    return sp.csc_matrix((values, (rows, cols)), shape=(n_equal + n_below + int(above.sum()), k))
