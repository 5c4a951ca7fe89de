"""The spread of each marker-neighbour distance over a labeled take (``take_spread``)."""

import numpy as np

from formulations.markers.state import MarkerState
from formulations.markers.take_spread import DECILE_SPAN_SD, MIN_FRAMES, SPREAD_FLOOR_MM2, _spread, take_spread, with_take_spread


def _take(seed: int, frames: int = 200, markers: int = 6) -> np.ndarray:
    """Markers wandering independently, some samples missing."""
    rng = np.random.default_rng(seed)
    positions = rng.normal(0.0, 30.0, (1, markers, 3)) + np.cumsum(rng.normal(0.0, 2.0, (frames, markers, 3)), axis=0)
    positions[rng.random((frames, markers)) < 0.2] = np.nan
    return positions


def test_each_pair_is_its_deciles_over_the_frames_both_are_labeled() -> None:
    positions = _take(0)
    neighbours = np.array([[j for j in range(6) if j != m][:4] for m in range(6)])
    spread = take_spread(positions, neighbours)
    for m in range(6):
        for k, j in enumerate(neighbours[m]):
            d = np.linalg.norm(positions[:, m] - positions[:, j], axis=1)
            d = d[np.isfinite(d)]
            low, high = np.percentile(d, [10, 90])
            assert spread[m, k] == max(((high - low) / DECILE_SPAN_SD) ** 2, SPREAD_FLOOR_MM2)


def test_pairs_seldom_labeled_together_are_unknown_and_keep_the_prior() -> None:
    positions = _take(1)
    positions[MIN_FRAMES - 1 :, 0] = np.nan  # marker 0 labeled in fewer than MIN_FRAMES frames
    neighbours = np.array([[1, 2], [0, 2], [0, 1], [0, 1], [0, 1], [0, 1]])
    spread = take_spread(positions, neighbours)
    assert np.isnan(spread[0]).all() and np.isnan(spread[1, 0]) and np.isfinite(spread[1, 1])
    state = MarkerState.from_first_frame(np.nan_to_num(positions[0]), n_neighbours=2)
    learned = with_take_spread(state, positions)
    assert (learned.distance_var[0] == state.distance_var[0]).all()


def test_a_rigid_pair_mislabeled_in_a_few_frames_stays_rigid() -> None:
    """A first pass that put a marker on another's point now and then does not make its
    rigid partner look loose, as the plain variance would."""
    rng = np.random.default_rng(2)
    frames = 300
    a = np.cumsum(rng.normal(0.0, 5.0, (frames, 3)), axis=0)
    b = a + np.array([60.0, 0.0, 0.0]) + rng.normal(0.0, 0.5, (frames, 3))
    far = a + np.array([0.0, 400.0, 0.0])
    positions = np.stack([a, b, far], axis=1)
    wrong = rng.choice(frames, size=frames // 20, replace=False)
    positions[wrong, 1] = far[wrong]  # b labeled on the far marker's point in 5 % of frames
    spread = take_spread(positions, np.array([[1, 2], [0, 2], [0, 1]]))
    plain = np.var(np.linalg.norm(positions[:, 0] - positions[:, 1], axis=1))
    assert spread[0, 0] < 4.0 < 1000.0 < plain


def test_the_deciles_are_numpys_percentiles_for_every_count_of_labeled_frames() -> None:
    """``_deciles`` writes out numpy's linear percentile for all rows at once: pinned to it."""
    from formulations.markers.take_spread import _deciles

    rng = np.random.default_rng(2)
    distance = rng.gamma(2.0, 50.0, (120, 61))
    for row, n in enumerate(range(2, 62)):  # n finite values: (n - 1) q whole or not
        distance[row, rng.permutation(61)[n:]] = np.nan
    distance[60:] = np.round(distance[60:], 0)  # ties
    assert np.array_equal(_deciles(distance), np.nanpercentile(distance, [10, 90], axis=1), equal_nan=True)


def test_a_labeling_read_again_gets_its_spread_kept_and_a_changed_one_its_own() -> None:
    positions = _take(3)
    neighbours = np.array([[j for j in range(6) if j != m][:4] for m in range(6)])
    first = take_spread(positions, neighbours)
    first[:] = -1.0  # the caller's copy: what is kept is not written into
    again = take_spread(positions.copy(), neighbours)
    assert np.array_equal(again, _spread(positions, neighbours), equal_nan=True)
    moved = positions.copy()
    moved[:, 0] *= 1.5
    assert np.array_equal(take_spread(moved, neighbours), _spread(moved, neighbours), equal_nan=True)
    assert not np.array_equal(take_spread(moved, neighbours), again, equal_nan=True)
