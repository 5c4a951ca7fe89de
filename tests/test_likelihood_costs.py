"""The window's negative log-likelihood costs and what they are learned from (issue 11)."""

import numpy as np
import pytest

from formulations.markers.cloud_candidates import CloudGating, cloud_candidates
from formulations.markers.motion import MOTION_DECAY, learn_drift, learn_motion
from formulations.markers.state import MarkerState
from formulations.window.likelihood import BURST_SHARE, BURST_WIDTH, step_loss


def _white_acceleration_tracks(frames: int, markers: int, q: float, sigma: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    track = np.cumsum(np.cumsum(rng.normal(0.0, q, (frames, markers, 3)), axis=0), axis=0)
    return track + rng.normal(0.0, sigma, track.shape)


def _learned_motion(q: float, sigma: float, decay: float) -> np.ndarray:
    """``learn_motion`` over the constant-velocity residuals of 30 white-acceleration tracks."""
    positions = _white_acceleration_tracks(600, 30, q, sigma, seed=4)
    var, samples = np.full(30, 100.0), np.zeros(30, int)
    for t in range(2, len(positions)):
        residual = positions[t] - 2 * positions[t - 1] + positions[t - 2]
        var, samples = learn_motion(var, samples, residual, np.ones(30, bool), decay)
    return var


@pytest.mark.parametrize("q,sigma", [(0.5, 1.0), (3.0, 1.5), (10.0, 4.0)])
def test_motion_variance_learns_the_constant_velocity_residual(q, sigma):
    """Var(x_t - 2 x_(t-1) + x_(t-2)) = 6 sigma^2 + q^2 per axis for white accelerations."""
    assert np.median(_learned_motion(q, sigma, decay=1.0)) == pytest.approx(6 * sigma**2 + q**2, rel=0.10)


@pytest.mark.parametrize("q,sigma", [(0.5, 1.0), (3.0, 1.5)])
def test_the_cost_envelope_sits_above_the_variance_but_within_its_tail(q, sigma):
    """The envelope the costs use: at least the variance, below the residual's 99th percentile."""
    variance = 6 * sigma**2 + q**2
    envelope = np.median(_learned_motion(q, sigma, decay=MOTION_DECAY))
    assert variance < envelope < 6.63 * variance  # chi^2_1's 99th percentile (a square per axis, averaged)


def test_the_state_learns_its_motion_while_a_marker_is_seen():
    positions = _white_acceleration_tracks(400, 10, 3.0, 1.5, seed=6)
    state = MarkerState.from_first_frame(positions[0])
    for frame in positions[1:]:
        state = state.advance(frame, np.ones(len(frame), bool))
    assert np.all(state.motion_samples == len(positions) - 2)  # a residual from the third frame on
    assert np.median(state.motion_var) > 6 * 1.5**2 + 3.0**2


def test_drift_variance_learns_how_fast_predictions_spread():
    """Reappearing after u frames at error e ~ N(0, motion_var + g^2 u) per axis teaches g^2."""
    rng = np.random.default_rng(5)
    n, g2, motion_var = 10, 12.0, np.full(10, 4.0)
    var, samples = np.full(n, 6.25), np.zeros(n, int)
    for _ in range(400):
        unseen = rng.integers(1, 40, n)
        residual = rng.normal(0.0, 1.0, (n, 3)) * np.sqrt(motion_var + g2 * unseen)[:, None]
        var, samples = learn_drift(var, samples, residual, rng.random(n) < 0.3, unseen, motion_var)
    assert var[0] == pytest.approx(g2, rel=0.15)
    assert np.all(var == var[0])


def test_step_loss_is_the_contaminated_gaussian_and_never_flat():
    """rho against the mixture density integrated numerically: Gaussian near 0, far slower beyond."""
    z = np.linspace(0, 60, 601)
    rho = step_loss(z)
    density = (1 - BURST_SHARE) * np.exp(-0.5 * z**2) + BURST_SHARE * BURST_WIDTH**-3 * np.exp(-0.5 * (z / BURST_WIDTH) ** 2)
    assert rho == pytest.approx(-np.log(density / density[0]))
    assert np.all(np.diff(rho) > 0)
    assert rho[z == 2][0] == pytest.approx(2.0, abs=0.05)  # the core: z^2 / 2
    assert rho[z == 20][0] < 0.2 * 0.5 * 20**2  # a burst costs far less than a Gaussian says


def _reappearing_marker(distances_mm: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """A marker unseen for a frame and candidates at the given distances from its prediction.

    Returns the reappear cost of each candidate under the likelihood and under the old
    capped prediction term (template cost, which is what the old arcs add to c_a).
    """
    state = MarkerState.from_first_frame(np.array([[0.0, 0.0, 0.0], [500.0, 0.0, 0.0], [0.0, 500.0, 0.0]]))
    for _ in range(5):
        state = state.advance(state.position, np.ones(3, bool))
    lost = np.array([False, True, True])
    state = state.advance(state.position, lost)
    frame = np.array([[d, 0.0, 0.0] for d in distances_mm] + [[500.0, 0.0, 0.0], [0.0, 500.0, 0.0]])
    new = cloud_candidates(state, [frame], CloudGating(shape_weight=0.0))
    old = cloud_candidates(state, [frame], CloudGating(shape_weight=0.0, likelihood=False))
    own = new.candidates.object == 0
    assert new.candidates.likelihood is not None
    return new.candidates.likelihood.reappear_cost[own], old.candidates.template_cost[old.candidates.object == 0]


def test_an_old_prediction_is_wide_but_never_capped():
    """The old term stopped growing at 6 sd (39 mm here): a marker's own point and one 8 mm further cost the same."""
    likelihood, capped = _reappearing_marker([42.0, 50.0, 58.0])
    assert capped[1] == pytest.approx(capped[2])  # fails without the feature: the cap
    assert likelihood[0] < likelihood[1] < likelihood[2]

