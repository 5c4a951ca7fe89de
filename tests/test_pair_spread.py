"""The take-wide judges' pair spreads (``formulations.markers.pair_spread``): each pair's robust
variance as a plain per-pair median computes it, whatever order and blocks it is asked in;
robust to a third of wrong labels; inf for a pair labeled together too rarely or a marker
with itself."""

import numpy as np

from formulations.markers.noise import MAD_TO_SIGMA
from formulations.markers.pair_spread import PairSpreads
from formulations.markers.take_spread import MIN_FRAMES, SPREAD_FLOOR_MM2


def _positions(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    positions = rng.normal(0, 100, (1, 5, 3)) + rng.normal(0, 2, (300, 5, 3))
    positions[rng.random((300, 5)) < 0.2] = np.nan
    positions[MIN_FRAMES // 2 :, 4] = np.nan  # marker 4 is labeled with the others too rarely
    return positions


def _direct(positions: np.ndarray, a: int, b: int) -> float:
    d = np.linalg.norm(positions[:, a] - positions[:, b], axis=1)
    d = d[np.isfinite(d)]
    if a == b or len(d) < MIN_FRAMES:
        return np.inf
    return max(float((MAD_TO_SIGMA * np.median(np.abs(d - np.median(d)))) ** 2), SPREAD_FLOOR_MM2)


def test_each_pair_as_a_direct_median_computes_it_in_any_blocks() -> None:
    for seed in range(3):
        positions = _positions(seed)
        spreads = PairSpreads(positions)
        first = spreads.var([3, 0], [1, 2, 3, 4])  # a block first, then every pair, some again
        every = spreads.var(list(range(5)), list(range(5)))
        direct = np.array([[_direct(positions, a, b) for b in range(5)] for a in range(5)])
        assert np.allclose(every, direct, rtol=1e-12) and np.array_equal(np.isinf(every), np.isinf(direct))
        assert np.allclose(first, direct[np.ix_([3, 0], [1, 2, 3, 4])], rtol=1e-12)
        assert np.isinf(np.diag(every)).all() and np.isinf(every[4, :4]).all()


def test_a_third_of_wrong_labels_leaves_a_rigid_pair_rigid() -> None:
    positions = _positions(0)[:, :4].copy()
    wrong = positions.copy()
    wrong[::3, [0, 1]] = positions[::3, [1, 0]]  # markers 0 and 1 exchanged in a third of the frames
    wrong[::3, 0] += 150.0  # and 0 off its segment there
    assert PairSpreads(wrong).rigid([0], [2, 3]).all()
    assert not PairSpreads(wrong).rigid([0], [0]).any()
