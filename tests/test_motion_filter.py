"""The per-marker Kalman filter (``markers.motion_filter``): markers a few noise widths apart.

At 4 mm of noise the raw constant-velocity prediction x_t + (x_t - x_(t-1)) errs by about
10 mm per axis, as much as half the spacing of a hand's markers: on the accuracy matrix's
validation takes at 4 mm (seeds 0-2) lp-l1 made 723 swaps without the filter, 283 with it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import formulations.markers.state as marker_state
from formulations.markers.motion_filter import MIN_NOISE_SD_MM, filter_holds, filter_predicts, filter_step
from formulations.markers.state import MarkerState
from service import Capture, CaptureLabeling

FRAMES, RATE = 300, 100.0


def _hand(frames: int = FRAMES) -> np.ndarray:
    """``(frames, 10, 3)``: a grid of markers 28 mm apart, drifting and turning slowly."""
    grid = np.array([[x, y, 0.0] for x in range(5) for y in range(2)]) * 28.0
    t = np.arange(frames)[:, None, None] / RATE
    turn = 0.3 * np.sin(2 * np.pi * 0.4 * t)
    rotated = np.concatenate([grid[..., :1] * np.cos(turn) - grid[..., 1:2] * np.sin(turn),
                              grid[..., :1] * np.sin(turn) + grid[..., 1:2] * np.cos(turn), grid[..., 2:] + 0 * t], axis=2)
    path = np.concatenate([200 * np.sin(2 * np.pi * 0.3 * t), 150 * np.cos(2 * np.pi * 0.2 * t), 1000 + 0 * t], axis=2)
    return rotated + path


def _forecast_errors(truth: np.ndarray, sigma: float) -> tuple[np.ndarray, np.ndarray, MarkerState]:
    """Median 3D error of the raw and of the state's forecast, after a settling second."""
    observed = truth + np.random.default_rng(1).normal(0, sigma, truth.shape)
    state = MarkerState.from_first_frame(observed[0])
    raw, used = [], []
    for f in range(1, len(truth)):
        if f > RATE:
            raw.append(np.linalg.norm(state._prediction[0] - truth[f], axis=1))
            used.append(np.linalg.norm(state.predict() - truth[f], axis=1))
        state = state.advance(observed[f], np.ones(len(truth[f]), bool))
    return np.median(raw), np.median(used), state


def test_filter_step_is_the_textbook_kalman_filter():
    rng = np.random.default_rng(3)
    n, r, q2 = 6, 4.0, rng.uniform(0.1, 3.0, 6)
    filtered = rng.normal(0, 10, (n, 2, 3))
    half = rng.normal(0, 1, (n, 2, 2))
    p = half @ half.transpose(0, 2, 1) + np.eye(2)
    cov = np.stack([p[:, 0, 0], p[:, 0, 1], p[:, 1, 1]], axis=1)
    observed = filtered[:, 0] + filtered[:, 1] + rng.normal(0, 1, (n, 3))
    seen = np.ones(n, bool)
    new, new_cov, _, _ = filter_step(filtered, cov, seen, observed, seen, seen, observed, r, 6 * r + q2, np.zeros(n))
    f_, h = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    for m in range(n):
        prior = f_ @ p[m] @ f_.T + q2[m] * np.array([[0.25, 0.5], [0.5, 1.0]])
        gain = prior @ h.T / (h @ prior @ h.T + r)
        state = f_ @ filtered[m] + gain @ (observed[m][None] - h @ f_ @ filtered[m])
        posterior = (np.eye(2) - gain @ h) @ prior
        assert np.allclose(new[m], state)
        assert np.allclose(new_cov[m], [posterior[0, 0], posterior[0, 1], posterior[1, 1]])


def test_the_take_noise_is_learned_within_ten_percent():
    *_, state = _forecast_errors(_hand(), 3.0)
    assert np.sqrt(state.noise_var[0]) == pytest.approx(3.0, rel=0.1)


def test_filtered_forecast_is_nearer_under_noise_and_no_worse_when_clean():
    raw, used, _ = _forecast_errors(_hand(), 4.0)
    assert used < 0.7 * raw
    raw, used, _ = _forecast_errors(_hand(), 0.05)
    assert used <= 1.05 * raw


def _mislabeled(truth: np.ndarray, sigma: float) -> int:
    observed = truth + np.random.default_rng(2).normal(0, sigma, truth.shape)
    names = [f"m{i}" for i in range(truth.shape[1])]
    labels, _ = CaptureLabeling(Capture(names, observed[0], RATE, points=list(observed))).label()
    return int((labels.point_index != np.arange(truth.shape[1])).sum())


def test_close_markers_keep_their_labels_under_4mm_noise():
    assert _mislabeled(_hand(), 4.0) == 0


def test_without_the_filter_they_are_exchanged(monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setattr(marker_state, "filter_predicts", lambda state: np.zeros(len(state.position), bool))
    assert _mislabeled(_hand(), 4.0) > 0


def _swing(frames: int = FRAMES) -> np.ndarray:
    """``(frames, 3, 3)``: three markers on a forearm swung through 1.2 rad at 3 Hz (a fast push)."""
    t = np.arange(frames)[:, None] / RATE
    angle = 0.6 * np.sin(2 * np.pi * 3.0 * t)
    radius = np.array([250.0, 280.0, 310.0])
    return np.stack([radius * np.sin(angle), -radius * np.cos(angle), np.full((frames, 3), 1000.0)], axis=2)


def test_a_swing_under_little_noise_is_predicted_raw():
    """The filter lags behind a swing its white acceleration does not expect: where the noise is
    small against the raw residual the raw prediction is used, though the filter holds."""
    truth = _swing()
    observed = truth + np.random.default_rng(4).normal(0, 0.5, truth.shape)
    state, holds = MarkerState.from_first_frame(observed[0]), 0
    for f in range(1, len(truth)):
        if f > RATE:
            assert np.array_equal(state.predict(), state._prediction[0])
            holds += int(filter_holds(state.filter_raw, state.position, state.visible).sum())
        state = state.advance(observed[f], np.ones(3, bool))
    assert holds > 0.5 * 3 * (len(truth) - 1 - RATE)


def test_the_filter_predicts_only_where_noise_is_half_the_residual_and_not_negligible():
    *_, state = _forecast_errors(_hand(), 4.0)
    assert filter_predicts(state).all()
    noise = float(state.noise_var[0])
    louder = replace(state, residual_var=np.full(len(state.position), 12.5 * noise), filter_var=state.filter_var * 0)
    assert not filter_predicts(louder).any()
    assert filter_predicts(replace(louder, residual_var=louder.residual_var * 11.5 / 12.5)).all()
    quiet = np.full(len(state.position), 0.9 * MIN_NOISE_SD_MM**2)
    assert not filter_predicts(replace(state, noise_var=quiet, residual_var=quiet, filter_var=quiet * 0)).any()
