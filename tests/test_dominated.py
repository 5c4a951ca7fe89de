"""Entries no k-best assignment takes: dropped, and the k best unchanged (brute force)."""

import numpy as np
import pytest
from test_murty import assert_ranks, every_assignment

from formulations.assignment.blocks import _blocks, k_best_assignments
from formulations.assignment.dominated import without_dominated


def cheap_misses(seed: int, rows: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Costs on [0, 10) with misses on [2, 6): many entries dearer than missing their row."""
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0, 10, size=(rows, width))
    cost[rng.random(cost.shape) < 0.15] = np.inf
    return cost, rng.uniform(2, 6, size=rows)


@pytest.mark.parametrize("seed", range(16))
def test_the_k_best_of_the_pruned_matrix_are_the_whole_matrix_k_best(seed):
    rows, width = 2 + seed % 4, 2 + seed % 5
    cost, miss = cheap_misses(seed, rows, width)
    truth = every_assignment(cost, miss)
    for k in (2, 3, 6, 20):
        pruned = without_dominated(cost, miss, k)
        assert_ranks(truth, k_best_assignments(pruned, miss, k), k)  # the pruned matrix alone
        assert_ranks(truth, k_best_assignments(cost, miss, k), k)


def test_entries_are_dropped_and_a_wide_row_no_longer_joins_the_block():
    """Row 0 (a lost marker's wide gate) reaches every column at a cost far over its miss;
    every other row has its own column. Unpruned, row 0 joins them all into one block."""
    cost = np.full((5, 4), np.inf)
    cost[0] = 50.0
    cost[np.arange(1, 5), np.arange(4)] = 1.0
    miss = np.full(5, 10.0)
    _, before = _blocks(np.isfinite(cost))
    pruned = without_dominated(cost, miss, k=3)
    _, after = _blocks(np.isfinite(pruned))
    assert [len(rows) for rows, _ in before] == [5]
    assert np.isinf(pruned[0]).all() and after == []
    truth = every_assignment(cost, miss)
    assert_ranks(truth, k_best_assignments(cost, miss, 3), 3)


def test_nothing_is_dropped_without_misses_or_for_the_best_alone():
    cost, miss = cheap_misses(3, 4, 4)
    assert without_dominated(cost, None, 5) is cost
    assert without_dominated(cost, miss, 1) is cost
    miss[1] = np.inf  # a row that must be assigned cannot be left out to beat it
    assert without_dominated(cost, miss, 5) is cost
