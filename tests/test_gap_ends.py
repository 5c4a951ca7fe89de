"""A gap's fill tied to the sightings on both sides (``formulations.markers.gap_ends``)."""

from __future__ import annotations

import numpy as np

from formulations.markers.gap_ends import open_gaps, tie_gap_ends


def _track(frames: int = 40) -> np.ndarray:
    """``(frames, 2, 3)``: two markers moving at constant velocity."""
    t = np.arange(frames, dtype=float)[:, None]
    return np.stack([np.hstack([3 * t, -2 * t, 0 * t + 5]), np.hstack([t, t, t]) + 100], axis=1)


def test_a_fill_that_drifts_linearly_is_brought_back_onto_the_track() -> None:
    truth = _track()
    positions = truth.copy()
    positions[10:18, 0] = np.nan  # closed gap of marker 0
    positions[30:, 1] = np.nan  # gap open at the end of marker 1
    filled = np.full_like(truth, np.nan)
    drift = np.arange(8, dtype=float)[:, None] * np.array([4.0, -1.0, 2.0]) + np.array([7.0, 0.0, -3.0])
    filled[10:18, 0] = truth[10:18, 0] + drift  # an offset at the start and a drift through the gap
    filled[30:, 1] = truth[30:, 1] + 25.0
    tied = tie_gap_ends(positions, filled)
    assert np.abs(filled[10:18, 0] - truth[10:18, 0]).max() > 30  # what the tie has to mend
    assert np.allclose(tied[10:18, 0], truth[10:18, 0], atol=1e-9)
    assert np.array_equal(tied[30:, 1], filled[30:, 1])  # one sighting: left as it was
    assert np.isnan(tied[~np.isnan(positions).any(axis=2)]).all()  # seen frames stay unfilled


def test_one_frame_gaps_are_tied_and_a_gap_open_at_the_start_is_left() -> None:
    truth = _track(12)
    positions = truth.copy()
    positions[[0, 5, 9], 0] = np.nan  # open at the start; two one-frame gaps
    filled = np.where(np.isnan(positions), truth + 9.0, np.nan)
    tied = tie_gap_ends(positions, filled)
    assert np.allclose(tied[5, 0], truth[5, 0]) and np.allclose(tied[9, 0], truth[9, 0])
    assert np.allclose(tied[0, 0], truth[0, 0] + 9.0)


def test_open_gaps_are_the_unseen_runs_at_either_end() -> None:
    seen = np.array([False, False, True, False, True, True, False])
    assert open_gaps(seen) == [(0, 1), (6, 6)]
    assert open_gaps(np.ones(4, bool)) == [] and open_gaps(np.zeros(4, bool)) == []
    assert open_gaps(np.array([True, False, True])) == []
