"""The k-best repair: on windows whose LP is fractional, lp-l1 returns cheaper paths, never dearer ones."""

from __future__ import annotations

import pytest
from integrality_corpus import FOLDER

from formulations.methods.lp_l1 import LpL1
from service.evaluation.integrality import load_corpus, solve_corpus

TOLERANCE = 1e-6


@pytest.fixture(scope="module")
def fractional() -> list[tuple[dict, object, object]]:
    """(record, unrepaired, repaired) for every corpus window whose LP optimum is fractional."""
    rows = []
    for name in sorted(load_corpus(FOLDER)):
        records, plain, _ = solve_corpus(FOLDER, name, LpL1(decompose=False, repair=0))
        _, repaired, _ = solve_corpus(FOLDER, name, LpL1(decompose=False))
        rows += [(r, p, s) for r, p, s in zip(records, plain, repaired) if not p.integral]
    return rows


def test_the_corpus_has_fractional_windows_the_rounding_leaves_above_the_optimum(fractional):
    """Without the repair the setup fails: greedy rounding is above the ILP optimum on several windows."""
    above = [r for r, plain, _ in fractional
             if plain.cost > r["ilp_optimum"] + TOLERANCE * max(1.0, abs(r["ilp_optimum"]))]
    assert len(fractional) >= 10 and len(above) >= 5


def test_repair_never_raises_the_cost_and_lowers_it_on_some_windows(fractional):
    lowered = 0
    for record, plain, repaired in fractional:
        scale = max(1.0, abs(record["ilp_optimum"]))
        assert record["ilp_optimum"] <= repaired.cost + TOLERANCE * scale, record["file"]
        assert repaired.cost <= plain.cost + TOLERANCE * scale, record["file"]
        assert plain.lower_bound - TOLERANCE * scale <= repaired.lower_bound <= record["ilp_optimum"] + TOLERANCE * scale
        lowered += repaired.cost < plain.cost - TOLERANCE * scale
        if repaired.integral:
            assert repaired.cost == pytest.approx(record["ilp_optimum"], abs=TOLERANCE * scale), record["file"]
    assert lowered >= 5

