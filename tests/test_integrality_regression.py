"""The integrality corpus: LP bound <= ILP optimum <= rounded cost, and no regression.

Windows and their recorded figures are fixture files written by
``tests/integrality_corpus.py``.
"""

import numpy as np
import pytest
from integrality_corpus import FOLDER

from formulations.methods.lp_l1 import LpL1
from service.evaluation.integrality import load_corpus, solve_corpus

RECORDED = load_corpus(FOLDER)
TOLERANCE = 1e-6


def relative_gap(cost: float, bound: float) -> float:
    return max(0.0, cost - bound) / max(abs(cost), 1e-9)


@pytest.fixture(scope="module", params=sorted(RECORDED))
def corpus(request):
    records, solutions, _ = solve_corpus(FOLDER, request.param, LpL1(decompose=False))
    return request.param, records, solutions


def test_corpus_covers_generated_and_real_windows():
    assert {"random-3x4", "jiang-3x10-clutter", "cmu-85-02-cloud", "cmu-135-02-cloud"} <= set(RECORDED)
    assert all(len(rows) >= 10 for rows in RECORDED.values())


def test_lp_bound_ilp_optimum_rounded_cost_are_ordered(corpus):
    name, records, solutions = corpus
    for record, solution in zip(records, solutions):
        scale = max(1.0, abs(record["ilp_optimum"]))
        assert solution.lower_bound == pytest.approx(record["lp_objective"], abs=TOLERANCE * scale), record["file"]
        assert solution.lower_bound <= record["ilp_optimum"] + TOLERANCE * scale, record["file"]
        assert record["ilp_optimum"] <= solution.cost + TOLERANCE * scale, record["file"]
        if solution.integral:
            assert solution.cost == pytest.approx(record["ilp_optimum"], abs=TOLERANCE * scale), record["file"]


def test_integrality_and_gaps_are_no_worse_than_recorded(corpus):
    name, records, solutions = corpus
    then_gaps = np.array([relative_gap(r["rounded_cost"], r["lp_objective"]) for r in records])
    now_gaps = np.array([s.gap for s in solutions])
    assert np.mean([s.integral for s in solutions]) >= np.mean([r["lp_integral"] for r in records]) - 1e-12
    assert np.median(now_gaps) <= np.median(then_gaps) + 1e-9
    assert now_gaps.max() <= then_gaps.max() + 1e-9
