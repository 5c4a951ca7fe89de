"""best-view windows past the take, costs too large to sum; formulation parameters of the wrong type or range."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from formulations.best_view import select_views
from formulations.errors import FormulationError
from formulations.methods.registry import get_formulation
from service.best_view.tables import read_view_costs
from service.capture.formulation_spec import formulation_from_table
from service.errors import InputError


def test_huge_window_is_the_takes_length():
    costs = np.random.default_rng(0).uniform(0, 1, (40, 3, 4))
    # A billion-frame window is clamped to the take (it would otherwise be a billion DP steps).
    assert np.array_equal(select_views(costs, 0.5, 1_000_000_000), select_views(costs, 0.5, 40))


def test_huge_cost_is_refused_naming_the_line(tmp_path):
    path = tmp_path / "costs.csv"
    path.write_text("frame,object,camera,cost\n0,a,c1,1e308\n0,a,c2,1e308\n1,a,c1,1e308\n1,a,c2,0\n")
    with pytest.raises(InputError, match=r":2: cost .* is out of range"):
        read_view_costs(path)


def test_huge_costs_never_overflow_in_select_views():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(FormulationError, match="costs must be"):
            select_views(np.full((3, 1, 2), 1e308), 1.0, 3)


@pytest.mark.parametrize(("name", "parameters", "match"), [
    ("ilp", {"decompose": "no"}, "'decompose' must be true or false"),
    ("ilp", {"lp_first": 1}, "'lp_first' must be true or false"),
    ("lp-l1", {"decompose": "no"}, "'decompose' must be true or false"),
    ("dp-extended", {"decompose": 0}, "'decompose' must be true or false"),
    ("lp-l1", {"integrality_tolerance": 2}, "'integrality_tolerance' must be < 0.5"),
    ("lp-l1", {"integrality_tolerance": 0.5}, "'integrality_tolerance' must be < 0.5"),
    ("qp-l2", {"integrality_tolerance": 0.7}, "'integrality_tolerance' must be < 0.5"),
    ("lp-l1", {"repair": 100000}, "'repair' must be <= 10000"),
    ("lp-l1", {"repair": 2.5}, "'repair' must be an integer"),
    ("lp-l1", {"pricing_successors": 2.5}, "'pricing_successors' must be an integer"),
    ("mht", {"hypotheses": 100000, "associations": 100000}, "'hypotheses' must be <= 10000"),
    ("mht", {"associations": 100000}, "'associations' must be <= 10000"),
])
def test_bad_formulation_parameters_are_named(name, parameters, match):
    with pytest.raises(FormulationError, match=match) as error:
        get_formulation(name, **parameters)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(("table", "match"), [
    ({"name": "mht", "hypotheses": 1000}, "'hypotheses' must be <= 100,"),
    ({"name": "mht", "associations": 101}, "'associations' must be <= 100,"),
    ({"name": "lp-l1", "repair": 1000}, "'repair' must be <= 100,"),
])
def test_a_users_table_asks_for_a_search_that_ends(table, match):
    with pytest.raises(InputError, match=match):
        formulation_from_table(table, "preset.toml")
    assert formulation_from_table({**table, **{k: 100 for k in table if k != "name"}}, "preset.toml")


def test_parameters_in_range_are_kept():
    assert get_formulation("lp-l1", integrality_tolerance=0.49, repair=100).repair == 100
    assert get_formulation("mht", hypotheses=100, associations=100).hypotheses == 100
    assert get_formulation("ilp", decompose=False).decompose is False
