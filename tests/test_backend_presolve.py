"""``set_presolve`` over every backend: the option reaches the solver, and the optimum with
presolve off is the one scipy's own LP solver finds."""

import numpy as np
import pytest
from scipy.optimize import linprog
from test_clarabel_backend import random_lp

from formulations.solvers import create_backend


@pytest.mark.parametrize("name", ["highs", "clarabel"])
@pytest.mark.parametrize("seed", range(4))
def test_an_lp_solved_as_given_has_scipys_optimum(name: str, seed: int) -> None:
    model = random_lp(seed)
    backend = create_backend(name)
    backend.set_presolve(False)
    backend.set_model(model)
    result = backend.solve()
    a = model.matrix.toarray()
    upper, lower = np.isfinite(model.row_upper), np.isfinite(model.row_lower)
    reference = linprog(model.cost, A_ub=np.vstack([a[upper], -a[lower]]),
                        b_ub=np.r_[model.row_upper[upper], -model.row_lower[lower]],
                        bounds=list(zip(model.col_lower, model.col_upper)), method="highs-ds")
    assert result.optimal and reference.status == 0
    assert float(model.cost @ result.x) == pytest.approx(reference.fun, abs=1e-6)


def test_the_presolve_option_reaches_each_solver() -> None:
    highs = create_backend("highs")
    for enabled, value in [(False, "off"), (True, "on")]:
        highs.set_presolve(enabled)
        assert highs._highs.getOptionValue("presolve")[1] == value  # type: ignore[attr-defined]
    clarabel = create_backend("clarabel")
    clarabel.set_presolve(False)
    assert clarabel._settings.presolve_enable is False  # type: ignore[attr-defined]
