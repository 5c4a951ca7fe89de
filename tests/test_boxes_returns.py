"""A lost object's return against a newcomer (``returns``) and the learned birth and return rates (``births``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from formulations.boxes import kalman
from formulations.boxes.births import PRIOR_EVENTS, PRIOR_EXPOSURE, BirthRates
from formulations.boxes.lifecycle import Lifecycle
from formulations.boxes.returns import filtered_nll, newcomer_nll, population_rates

F = np.block([[np.eye(4), np.eye(4)], [np.zeros((4, 4)), np.eye(4)]])
H = np.hstack([np.eye(4), np.zeros((4, 4))])


def _joint_nll(mean, covariance, t0, frames, z):
    """Brute force: -log of the joint Gaussian density of all the measurements at once, from
    the state at t0 pushed through x' = F x + w, z = H x + v with the box-size noises of ``kalman``
    (the size is held fixed here, so they are constant)."""
    size = np.r_[mean[2:4], mean[2:4]]
    q = np.diag(np.r_[(kalman.POSITION_SD * size) ** 2, (kalman.VELOCITY_SD * size) ** 2])
    r = np.diag((kalman.MEASUREMENT_SD * size) ** 2)
    last = int(frames.max())
    state_cov = {t0: covariance}
    for t in range(t0 + 1, last + 1):
        state_cov[t] = F @ state_cov[t - 1] @ F.T + q
    k = len(frames)
    joint = np.zeros((4 * k, 4 * k))
    for i, a in enumerate(frames):
        for j, b in enumerate(frames):
            lo, hi = min(a, b), max(a, b)
            cross = np.linalg.matrix_power(F, int(hi - lo)) @ state_cov[int(lo)]  # cov(x_hi, x_lo)
            block = H @ (cross.T if a <= b else cross) @ H.T  # cov(z_a, z_b)
            joint[4 * i:4 * i + 4, 4 * j:4 * j + 4] = block + (r if i == j else 0.0)
    expected = np.concatenate([H @ np.linalg.matrix_power(F, int(f - t0)) @ mean for f in frames])
    return -multivariate_normal(expected, joint).logpdf(z.ravel())


@pytest.mark.parametrize("seed", range(3))
def test_filtered_likelihood_is_the_joint_density_of_the_chain(seed):
    rng = np.random.default_rng(seed)
    mean = np.r_[300.0, 200.0, 40.0, 100.0, rng.normal(0, 3, 2), 0.0, 0.0]  # sizes fixed: constant noises
    covariance = kalman.start(mean[None, :4], mean[None, 4:])[1][0]
    frames = np.array([13, 14, 16, 17]) + seed  # a gap inside the chain too
    z = np.column_stack([300 + rng.normal(0, 20, 4), 200 + rng.normal(0, 10, 4), np.full(4, 40.0), np.full(4, 100.0)])
    assert filtered_nll(mean, covariance, 10, frames, z) == pytest.approx(_joint_nll(mean, covariance, 10, frames, z))


def test_a_newcomers_first_box_is_uniform_and_its_velocity_comes_from_the_population():
    z = np.array([[320.0, 240.0, 40.0, 100.0], [323.0, 241.0, 40.0, 100.0], [326.0, 240.0, 40.0, 100.0]])
    frames = np.array([5, 6, 7])
    assert newcomer_nll(frames[:1], z[:1], 1e9) == pytest.approx(np.log(1e9))
    rates = np.array([[0.075, 0.0, 0.0, 0.0], [1e-4, 1e-4, 1e-4, 1e-4]])  # 3 px per frame for a 40 px wide box
    mean, covariance = kalman.start(z[:1])
    mean[0, 4:] = [3.0, 0.0, 0.0, 0.0]
    covariance[0, 4:, 4:] = np.diag(1e-4 * np.r_[40.0, 100.0, 40.0, 100.0] ** 2)
    expected = np.log(1e9) + filtered_nll(mean[0], covariance[0], 5, frames[1:], z[1:])
    assert newcomer_nll(frames, z, 1e9, rates) == pytest.approx(expected)
    assert newcomer_nll(frames, z, 1e9, rates) < newcomer_nll(frames, z, 1e9)  # the walk was foreseen


def test_population_rates_are_per_box_size():
    rng = np.random.default_rng(4)
    n = 5
    size = rng.uniform(20, 200, (n, 2))
    rate = rng.normal(0, 0.05, (n, 4))
    mean = np.column_stack([rng.uniform(0, 500, (n, 2)), size, rate * np.c_[size, size]])
    covariance = np.stack([np.diag(rng.uniform(0.1, 2.0, 8)) for _ in range(n)])
    got = population_rates(mean, covariance)
    assert got is not None
    own = np.array([np.diag(c)[4:] / np.r_[s, s] ** 2 for c, s in zip(covariance, size)])
    np.testing.assert_allclose(got[0], rate.mean(axis=0))
    np.testing.assert_allclose(got[1], rate.var(axis=0, ddof=1) + own.mean(axis=0))
    assert population_rates(mean[:2], covariance[:2]) is None


def test_birth_and_return_counts_against_a_loop():
    rng = np.random.default_rng(5)
    taken = np.where(rng.random((6, 4)) < 0.5, rng.integers(0, 50, (6, 4)), -1)
    last_seen = np.array([20, 20, 17, 15, 20, 19])
    lost = np.array([True, True, True, True, True, False])
    returns = unseen = 0
    for n in range(6):
        seen_before = last_seen[n] >= 20
        for m in range(4):
            if lost[n] and not seen_before:
                unseen += 1
                returns += int(taken[n, m] >= 0)
            seen_before = taken[n, m] >= 0
    rates = BirthRates().counted(2, 4, last_seen, taken, 20, lost)
    assert (rates.births, rates.frames, rates.returns, rates.unseen) == (2, 4, returns, unseen)
    assert rates.birth_rate == pytest.approx((2 + PRIOR_EVENTS) / (4 + PRIOR_EXPOSURE))
    assert rates.return_rate == pytest.approx((returns + PRIOR_EVENTS) / (unseen + PRIOR_EXPOSURE))
    assert rates.newcomer_cost == pytest.approx(np.log(rates.return_rate / rates.birth_rate))
    assert BirthRates().newcomer_cost == 0.0  # no counts: equal odds


def test_window_chains_run_past_the_window_only_with_a_returned_box():
    # Two people, one box per frame each, in frames 10..20; the window is t0 = 10, M = 4.
    frame = np.repeat(np.arange(10, 21), 2)
    boxes = np.array([[100.0 + 2 * f + 300 * p, 100.0, 140.0 + 2 * f + 300 * p, 200.0] for f in range(10, 21) for p in range(2)])
    rule = Lifecycle(min_hits=3)
    free = frame >= 13  # both first free in the window's last two frames, 13 and 14
    returned = (frame == 13) & (boxes[:, 0] < 300)  # person 0's box at 13: taken after a miss
    chains = rule.window_chains(frame, boxes, free, returned, 10, 4, 20)
    assert len(chains) == 1 and (boxes[chains[0], 0] < 300).all()
    assert frame[chains[0]].tolist() == [13, 14, 15, 16, 17, 18]  # M = 4 frames past the window
    assert frame[rule.window_chains(frame, boxes, free, returned, 10, 4, 16)[0]].tolist() == [13, 14, 15, 16]
    # Without the returned box neither chain has 3 boxes in the window; with the window
    # longer, both do, cut at its end.
    assert rule.window_chains(frame, boxes, free, np.zeros_like(returned), 10, 4, 20) == []
    longer = rule.window_chains(frame, boxes, free, np.zeros_like(returned), 10, 5, 20)
    assert sorted(frame[c].tolist() for c in longer) == [[13, 14, 15], [13, 14, 15]]
