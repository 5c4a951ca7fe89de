"""HiGHS through highspy, fed directly from scipy sparse matrices."""

from __future__ import annotations

import time

import highspy
import numpy as np
import scipy.sparse as sp

from formulations.errors import SolverFailure
from formulations.solvers.base import LinearModel, SolverBackend, SolveResult

PRIMAL_SIMPLEX = 4  # HiGHS simplex_strategy: primal


class _SilentHighs(highspy.Highs):
    """``highspy.Highs`` that prints nothing, not even on construction.

    From highspy 1.16 the constructor registers its callback, a logged call, before any
    option can be set, so every instance printed the licence banner on stdout (and broke
    ``--json`` output). The constructor's ``enableCallbacks`` is where it happens; logging
    is switched off first.
    """

    def __init__(self) -> None:
        super().__init__()  # type: ignore[no-untyped-call]
        self.setOptionValue("output_flag", False)  # whether or not the constructor reached the hook below

    def enableCallbacks(self) -> None:  # noqa: N802  # highspy's name
        self.setOptionValue("output_flag", False)
        super().enableCallbacks()  # type: ignore[no-untyped-call]


class HighsBackend(SolverBackend):
    """Dual simplex for LPs (warm-startable after adding columns), branch and bound for MIPs."""

    def __init__(self) -> None:
        self._highs = _SilentHighs()
        # One thread: windows are solved many at a time by the caller; HiGHS' parallel
        # simplex only adds overhead on problems this small.
        self._set("threads", 1)
        self._is_mip = False

    def set_timeout(self, seconds: float | None) -> None:
        self._set("time_limit", float(seconds) if seconds else highspy.kHighsInf)

    def set_relative_gap(self, gap: float) -> None:
        self._set("mip_rel_gap", float(gap))

    def set_primal_simplex(self) -> None:
        self._set("solver", "simplex")
        self._set("presolve", "choose")
        self._set("simplex_strategy", PRIMAL_SIMPLEX)

    def set_interior_point(self, tolerance: float = 1e-8) -> None:
        self._set("solver", "ipm")
        self._set("ipm_optimality_tolerance", float(tolerance))
        self._set("run_crossover", "off")
        # Without crossover, duals carried back through presolve are not the loaded model's
        # (columns already in it price negative): solve the model as given.
        self._set("presolve", "off")

    def set_presolve(self, enabled: bool) -> None:
        self._set("presolve", "on" if enabled else "off")

    def _set(self, name: str, value: bool | int | float | str) -> None:
        if self._highs.setOptionValue(name, value) != highspy.HighsStatus.kOk:
            raise ValueError(f"HiGHS rejected option {name}={value!r}")

    def set_model(self, model: LinearModel) -> None:
        a = sp.csc_matrix(model.matrix)
        a.sort_indices()
        lp = highspy.HighsLp()
        lp.num_col_, lp.num_row_ = a.shape[1], a.shape[0]
        lp.col_cost_ = np.asarray(model.cost, dtype=float)
        lp.col_lower_ = np.asarray(model.col_lower, dtype=float)
        lp.col_upper_ = np.asarray(model.col_upper, dtype=float)
        lp.row_lower_ = np.asarray(model.row_lower, dtype=float)
        lp.row_upper_ = np.asarray(model.row_upper, dtype=float)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = a.indptr.astype(np.int32)
        lp.a_matrix_.index_ = a.indices.astype(np.int32)
        lp.a_matrix_.value_ = a.data.astype(float)
        integer = model.integer if model.integer is not None else np.zeros(0, dtype=bool)
        self._is_mip = bool(np.any(integer))
        if self._is_mip:
            lp.integrality_ = [
                highspy.HighsVarType.kInteger if flag else highspy.HighsVarType.kContinuous for flag in integer
            ]
        self._highs.clearModel()
        self._highs.passModel(lp)

    @property
    def model(self) -> LinearModel:
        lp = self._highs.getLp()
        matrix = sp.csc_matrix((np.asarray(lp.a_matrix_.value_), np.asarray(lp.a_matrix_.index_),
                                np.asarray(lp.a_matrix_.start_)), shape=(lp.num_row_, lp.num_col_))
        integer = np.asarray([t == highspy.HighsVarType.kInteger for t in lp.integrality_], bool) if self._is_mip else None
        return LinearModel(np.asarray(lp.col_cost_), matrix, np.asarray(lp.row_lower_), np.asarray(lp.row_upper_),
                           np.asarray(lp.col_lower_), np.asarray(lp.col_upper_), integer)

    def add_columns(self, cost: np.ndarray, lower: np.ndarray, upper: np.ndarray, columns: sp.csc_matrix) -> None:
        cols = sp.csc_matrix(columns)
        cols.sort_indices()
        self._highs.addCols(
            len(cost), np.asarray(cost, float), np.asarray(lower, float), np.asarray(upper, float),
            cols.nnz, cols.indptr[:-1].astype(np.int32), cols.indices.astype(np.int32), cols.data.astype(float),
        )

    def add_rows(self, lower: np.ndarray, upper: np.ndarray) -> None:
        k = len(lower)
        self._highs.addRows(k, np.asarray(lower, float), np.asarray(upper, float), 0, np.zeros(k, np.int32),
                            np.zeros(0, np.int32), np.zeros(0))

    def solve(self) -> SolveResult:
        start = time.perf_counter()
        if self._highs.run() == highspy.HighsStatus.kError:
            # HiGHS' thread scheduler is one per process: once another HiGHS (cvxpy's, a
            # user's) started it with more threads, every run asking threads=1 is refused,
            # silently with output off. Take the scheduler as it is.
            self._set("threads", 0)
            if self._highs.run() == highspy.HighsStatus.kError:
                failed = self._highs.modelStatusToString(self._highs.getModelStatus())
                raise SolverFailure(f"HiGHS stopped with an error (model status {failed!r})")
        seconds = time.perf_counter() - start
        status = self._highs.getModelStatus()
        text = self._highs.modelStatusToString(status)
        solution = self._highs.getSolution()
        info = self._highs.getInfo()
        has_x = solution.value_valid
        x = np.asarray(solution.col_value) if has_x else np.zeros(0)
        objective = info.objective_function_value if has_x else float("nan")
        bound = info.mip_dual_bound if self._is_mip else objective
        duals = np.asarray(solution.row_dual) if solution.dual_valid else np.zeros(0)
        return SolveResult(
            status=text, optimal=status == highspy.HighsModelStatus.kOptimal,
            objective=objective, x=x, row_dual=duals, bound=bound, seconds=seconds,
        )
