"""Murty's k-best assignments against a brute-force ranking of every assignment."""

import itertools

import numpy as np
import pytest

from formulations.assignment import rankings
from formulations.assignment.blocks import k_best_assignments
from formulations.assignment.murty import ranked_assignments
from formulations.assignment.rankings import RankingCache


def every_assignment(cost: np.ndarray, miss: np.ndarray | None) -> list[tuple[float, tuple[int, ...]]]:
    """All finite-cost assignments (column per row, -1 unassigned), enumerated by a plain loop."""
    rows, width = cost.shape
    options = list(range(width)) + ([-1] if miss is not None else [])
    found = []
    for columns in itertools.product(options, repeat=rows):
        taken = [c for c in columns if c >= 0]
        if len(taken) != len(set(taken)):
            continue
        total = sum(miss[i] if c < 0 else cost[i, c] for i, c in enumerate(columns))
        if np.isfinite(total):
            found.append((float(total), columns))
    return sorted(found)


def assert_ranked_like_brute_force(cost, miss, k):
    """Both the block-wise ranking and Murty's on the whole matrix match the enumeration."""
    truth = every_assignment(cost, miss)
    assert_ranks(truth, k_best_assignments(cost, miss, k), k)
    assert_ranks(truth, list(itertools.islice(ranked_assignments(cost, miss), k)), k)


def assert_ranks(truth, ranked, k):
    assert len(ranked) == min(k, len(truth))
    assert [a.cost for a in ranked] == pytest.approx([t[0] for t in truth[: len(ranked)]])
    by_columns = dict((columns, total) for total, columns in truth)
    seen = set()
    for assignment in ranked:
        key = tuple(assignment.columns.tolist())
        assert key in by_columns, "not a feasible assignment"
        assert by_columns[key] == pytest.approx(assignment.cost)
        assert key not in seen, "an assignment reported twice"
        seen.add(key)


@pytest.mark.parametrize("seed", range(12))
def test_k_best_equal_brute_force_with_miss_costs_rectangular(seed):
    rng = np.random.default_rng(seed)
    rows, width = rng.integers(1, 5), rng.integers(1, 5)
    cost = rng.uniform(0, 10, size=(rows, width))
    cost[rng.random(cost.shape) < 0.2] = np.inf  # forbidden pairs
    miss = rng.uniform(0, 10, size=rows)
    miss[rng.random(rows) < 0.2] = np.inf  # rows that must be assigned
    assert_ranked_like_brute_force(cost, miss, k=int(rng.integers(1, 30)))


@pytest.mark.parametrize("seed", range(8))
def test_k_best_equal_brute_force_with_ties(seed):
    """Integer costs from a small range: many assignments share a cost."""
    rng = np.random.default_rng(100 + seed)
    cost = rng.integers(0, 3, size=(4, 4)).astype(float)
    miss = rng.integers(0, 3, size=4).astype(float)
    assert_ranked_like_brute_force(cost, miss, k=40)
    assert_ranked_like_brute_force(cost, None, k=10)


@pytest.mark.parametrize("seed", range(8))
def test_k_best_equal_brute_force_on_independent_blocks(seed):
    """Lone rows and blocks of contending rows, as in a window of markers: ranked by merging."""
    rng = np.random.default_rng(200 + seed)
    cost = np.full((5, 6), np.inf)
    cost[0, 0], cost[1, 1] = rng.integers(0, 3, size=2)  # two lone rows with one column each
    cost[2, 2:4], cost[3, 3:5] = rng.integers(0, 3, size=(2, 2))  # rows 2-3 contend for column 3
    cost[4, 5] = rng.integers(0, 3)
    miss = rng.integers(0, 4, size=5).astype(float)
    assert_ranked_like_brute_force(cost, miss, k=int(rng.integers(2, 40)))


@pytest.mark.parametrize("shape", [(3, 5), (2, 4), (4, 4)])
def test_without_miss_costs_every_row_is_assigned(shape):
    cost = np.random.default_rng(sum(shape)).uniform(0, 5, size=shape)
    assert_ranked_like_brute_force(cost, None, k=1000)  # k beyond the number of assignments


def test_k_beyond_the_number_of_assignments_returns_them_all():
    cost = np.array([[1.0, np.inf], [2.0, 3.0]])
    miss = np.array([np.inf, 5.0])
    ranked = k_best_assignments(cost, miss, k=10)
    assert [(a.cost, a.columns.tolist()) for a in ranked] == [(4.0, [0, 1]), (6.0, [0, -1])]


def test_no_assignment_at_all():
    assert k_best_assignments(np.full((2, 1), np.inf), None, k=3) == []
    assert k_best_assignments(np.ones((2, 1)), None, k=3) == []  # more rows than columns, no misses


def test_the_ranking_is_lazy():
    """A large problem yields its first few assignments without enumerating the rest."""
    cost = np.random.default_rng(0).uniform(0, 1, size=(40, 60))
    first = list(itertools.islice(ranked_assignments(cost, np.full(40, 2.0)), 5))
    assert len(first) == 5 and all(a.cost <= b.cost + 1e-12 for a, b in itertools.pairwise(first))


@pytest.mark.parametrize("seed", range(8))
def test_blocks_ranked_by_murty_equal_brute_force(monkeypatch, seed):
    """Blocks too large to enumerate are ranked by Murty's algorithm and merged by its lazy bounds."""
    monkeypatch.setattr(rankings, "ENUMERATION_LIMIT", 0)
    rng = np.random.default_rng(300 + seed)
    cost = rng.integers(0, 4, size=(6, 6)).astype(float)
    cost[rng.random(cost.shape) < 0.6] = np.inf  # sparse: several blocks, some of one row
    miss = rng.integers(1, 5, size=6).astype(float)
    truth = every_assignment(cost, miss)
    k = int(rng.integers(2, 30))
    assert_ranks(truth, k_best_assignments(cost, miss, k), k)
    assert_ranks(truth, k_best_assignments(cost, miss, k, RankingCache()), k)


def test_a_shared_cache_ranks_a_recurring_block_once_and_answers_alike():
    """Two matrices that share a block (hypotheses from one parent): the same rankings as
    without the cache, and the shared block ranked once."""
    rng = np.random.default_rng(7)
    first = np.full((5, 6), np.inf)
    first[0:2, 0:2] = rng.uniform(0, 3, size=(2, 2))  # the shared block
    first[2:4, 2:4] = rng.uniform(0, 3, size=(2, 2))
    first[4, 4:6] = rng.uniform(0, 3, size=2)
    second = first.copy()
    second[2:4, 2:4] = rng.uniform(0, 3, size=(2, 2))  # a different block in the other hypothesis
    miss = rng.uniform(1, 4, size=5)
    cache = RankingCache()
    for cost in (first, second):
        shared = k_best_assignments(cost, miss, 12, cache)
        alone = k_best_assignments(cost, miss, 12)
        assert [a.cost for a in shared] == [a.cost for a in alone]
        assert [a.columns.tolist() for a in shared] == [a.columns.tolist() for a in alone]
        assert_ranks(every_assignment(cost, miss), shared, 12)
    assert len(cache.rankings) == 3  # rows 0-1 once, rows 2-3 twice (different costs)
