"""The Clarabel LP backend against HiGHS: same optimum, same row duals in the same sign
convention, on LPs with every kind of row (equal, <=, >=, two-sided) and added rows and columns."""

import numpy as np
import pytest
import scipy.sparse as sp

from formulations.solvers import LinearModel, create_backend


def random_lp(seed: int) -> LinearModel:
    """A bounded, feasible LP whose optimum is unique (random data): x = x0 is feasible."""
    rng = np.random.default_rng(seed)
    m, n = 6, 10
    a = sp.random(m, n, density=0.6, random_state=seed, data_rvs=lambda k: rng.uniform(0.5, 2.0, k)).tocsc()
    x0 = rng.uniform(0.2, 1.0, n)
    ax = a @ x0
    kind = np.arange(m) % 4  # 0 equal, 1 <=, 2 >=, 3 two-sided
    lower = np.where(kind == 1, -np.inf, np.where(kind == 0, ax, ax - 1.0))
    upper = np.where(kind == 2, np.inf, np.where(kind == 0, ax, ax + 1.0))
    return LinearModel(cost=rng.normal(size=n), matrix=a, row_lower=lower, row_upper=upper,
                       col_lower=np.zeros(n), col_upper=np.full(n, 2.0))


def solved(name: str, model: LinearModel, grow: bool):
    backend = create_backend(name)
    if name == "clarabel":
        backend.set_interior_point(1e-10)
    if not grow:
        backend.set_model(model)
        return backend.solve()
    # the model, its last row (empty but for the last three columns) and columns added after loading
    a = sp.csc_matrix(model.matrix)
    backend.set_model(LinearModel(model.cost[:-3], a[:-1, :-3], model.row_lower[:-1], model.row_upper[:-1],
                                  model.col_lower[:-3], model.col_upper[:-3]))
    backend.add_rows(model.row_lower[-1:], model.row_upper[-1:])
    backend.add_columns(model.cost[-3:], model.col_lower[-3:], model.col_upper[-3:], a[:, -3:])
    return backend.solve()


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("grow", [False, True])
def test_same_optimum_and_row_duals_as_highs(seed, grow):
    model = random_lp(seed)
    reference, interior = solved("highs", model, grow), solved("clarabel", model, grow)
    assert reference.optimal and interior.optimal
    assert interior.objective == pytest.approx(reference.objective, abs=1e-6)
    assert np.allclose(interior.row_dual, reference.row_dual, atol=1e-5)


def test_refuses_what_it_cannot_do():
    backend = create_backend("clarabel")
    with pytest.raises(NotImplementedError):
        backend.set_primal_simplex()
    model = random_lp(0)
    model.integer = np.ones(len(model.cost), bool)
    with pytest.raises(ValueError, match="no MIP"):
        backend.set_model(model)


def test_a_grown_model_carries_from_one_backend_to_the_other():
    model = random_lp(3)
    a = sp.csc_matrix(model.matrix)
    highs = create_backend("highs")
    highs.set_model(LinearModel(model.cost[:-3], a[:-1, :-3], model.row_lower[:-1], model.row_upper[:-1],
                                model.col_lower[:-3], model.col_upper[:-3]))
    highs.add_rows(model.row_lower[-1:], model.row_upper[-1:])
    highs.add_columns(model.cost[-3:], model.col_lower[-3:], model.col_upper[-3:], a[:, -3:])
    carried = highs.model
    grown = a.tolil()
    grown[-1, :-3] = 0  # the added row was empty until the columns came
    assert (carried.matrix != grown.tocsc()).nnz == 0
    assert np.array_equal(carried.row_lower, model.row_lower) and np.array_equal(carried.cost, model.cost)
    interior = create_backend("clarabel")
    interior.set_model(carried)
    assert interior.solve().objective == pytest.approx(highs.solve().objective, abs=1e-6)
