"""Rigid alignment, marker prediction through occlusion, gated assignment, the take's noise."""

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.markers.guide import assign_nearest
from formulations.markers.noise import TakeNoise, measurement_noise
from formulations.markers.rigid import rigid_transform
from formulations.markers.state import MarkerState


def test_rigid_transform_recovers_rotation_and_translation():
    rng = np.random.default_rng(0)
    rotation = Rotation.random(20, random_state=1).as_matrix()
    source = rng.normal(size=(20, 5, 3))
    target = np.einsum("sij,skj->ski", rotation, source) + rng.normal(size=(20, 1, 3))
    found, c_s, c_t = rigid_transform(source, target, np.ones((20, 5)))
    assert np.allclose(found, rotation, atol=1e-9)
    assert np.allclose(np.einsum("sij,skj->ski", found, source - c_s[:, None]) + c_t[:, None], target, atol=1e-9)
    assert np.allclose(np.linalg.det(found), 1.0)


def test_rigid_transform_never_reflects():
    """Planar points admit a reflection with the same fit; the fix keeps det(R) = +1."""
    rng = np.random.default_rng(3)
    source = np.concatenate([rng.normal(size=(8, 4, 2)), np.zeros((8, 4, 1))], axis=2)
    mirrored = source * np.array([1.0, 1.0, -1.0])
    found, _, _ = rigid_transform(source, mirrored, np.ones((8, 4)))
    assert np.allclose(np.linalg.det(found), 1.0)


def _spinning_body(frames: int = 60) -> np.ndarray:
    """Six markers on one rigid body translating and spinning fast: (frames, 6, 3) mm."""
    body = np.array([[0, 0, 0], [80, 0, 0], [0, 90, 0], [0, 0, 100], [70, 60, 0], [40, 0, 90]], float)
    angle = np.linspace(0, 6.0, frames)
    spin = Rotation.from_rotvec(np.outer(angle, [0.3, 0.2, 0.93])).as_matrix()
    return np.einsum("fij,kj->fki", spin, body) + np.outer(np.arange(frames) * 12.0, [1, 0.5, 0])[:, None]


def _occlusion_error(positions: np.ndarray, hidden: int, gap: slice, follow_neighbours: bool) -> float:
    """Worst prediction error of the hidden marker over the gap."""
    state = MarkerState.from_first_frame(positions[0], n_neighbours=5)
    worst = 0.0
    for f in range(1, len(positions)):
        seen = np.ones(positions.shape[1], bool)
        if f == gap.start:
            last, velocity = state.position[hidden].copy(), state.velocity[hidden].copy()
        if gap.start <= f < gap.stop:
            seen[hidden] = False
            ballistic = last + velocity * (f - gap.start + 1)
            predicted = state.predict()[hidden] if follow_neighbours else ballistic
            worst = max(worst, float(np.linalg.norm(predicted - positions[f, hidden])))
        state = state.advance(positions[f], seen)
    return worst


def test_occluded_marker_follows_its_rigid_neighbours():
    positions = _spinning_body()
    # Without the neighbours, constant velocity drifts far off on a spinning body ...
    assert _occlusion_error(positions, hidden=4, gap=slice(30, 45), follow_neighbours=False) > 30.0
    # ... with them the occluded marker is carried along (what is left is the neighbours'
    # own one-frame extrapolation).
    assert _occlusion_error(positions, hidden=4, gap=slice(30, 45), follow_neighbours=True) < 2.0


def test_distance_variance_separates_rigid_from_loose_neighbours():
    positions = _spinning_body(frames=400)
    t = np.arange(len(positions))
    swing = np.stack([200 + 150 * np.sin(t / 5), np.zeros_like(t), np.zeros_like(t)], axis=1)
    loose = positions[:, :1] + swing[:, None]
    with_loose = np.concatenate([positions, loose], axis=1)
    state = MarkerState.from_first_frame(with_loose[0], n_neighbours=6)
    for f in range(1, len(with_loose)):
        state = state.advance(with_loose[f], np.ones(7, bool))
    loose_column = state.neighbours[0] == 6
    assert state.distance_var[0, loose_column].min() > 20 * state.distance_var[0, ~loose_column].max()


@pytest.mark.parametrize("seed", range(20))
def test_assign_nearest_is_the_optimal_gated_assignment(seed):
    rng = np.random.default_rng(seed)
    predicted, points = rng.uniform(0, 100, (4, 3)), rng.uniform(0, 100, (5, 3))
    radius, miss = np.full(4, 45.0), 30.0
    found = assign_nearest(predicted, points, radius, miss_cost=miss)
    distance = np.linalg.norm(predicted[:, None] - points[None], axis=2)

    def cost(choice):
        return sum(miss if c < 0 else distance[n, c] for n, c in enumerate(choice))

    feasible = [
        c for c in itertools.product(range(-1, 5), repeat=4)
        if len({x for x in c if x >= 0}) == sum(x >= 0 for x in c)
        and all(x < 0 or distance[n, x] <= radius[n] for n, x in enumerate(c))
    ]
    assert cost(found) == pytest.approx(min(cost(c) for c in feasible))


def _smooth_takes(frames: int = 1200, markers: int = 20, seed: int = 0) -> np.ndarray:
    """Limb-like tracks at 120 Hz: sums of 0.3-2 Hz sinusoids of 20-250 mm, (frames, markers, 3) mm."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames)[:, None, None, None] / 120.0
    amplitude = rng.uniform(20, 250, (1, markers, 3, 4))
    frequency = rng.uniform(0.3, 2.0, (1, markers, 3, 4))
    phase = rng.uniform(0, 2 * np.pi, (1, markers, 3, 4))
    return (amplitude * np.sin(2 * np.pi * frequency * t + phase)).sum(axis=3)


@pytest.mark.parametrize("sigma", [0.5, 1.5, 4.0])
def test_measurement_noise_recovers_a_known_sigma(sigma):
    rng = np.random.default_rng(1)
    positions = _smooth_takes() + rng.normal(0.0, sigma, (1200, 20, 3))
    positions[rng.random((1200, 20)) < 0.2] = np.nan  # gaps: only runs of 4 frames count
    found = measurement_noise(positions)
    assert found == pytest.approx(np.full(3, sigma), rel=0.10)


def test_take_noise_separates_acceleration_from_measurement():
    """q is D^2 x's scale less the noise's 6 sigma^2."""
    rng = np.random.default_rng(2)
    clean = _smooth_takes()
    noise = TakeNoise.of(clean + rng.normal(0.0, 1.5, clean.shape))
    truth = 1.4826 * np.median(np.abs(np.diff(clean, n=2, axis=0)).reshape(-1, 3), axis=0)
    assert noise.acceleration_mm == pytest.approx(truth, rel=0.15)


def test_prediction_sigma_matches_simulated_constant_velocity_extrapolation():
    """Tracks with white accelerations (q) seen with noise (sigma), extrapolated k frames."""
    rng = np.random.default_rng(3)
    sigma, q, k = 1.5, 0.8, np.array([0, 1, 10, 36])
    track = np.cumsum(np.cumsum(rng.normal(0.0, q, (20000, 39, 3)), axis=1), axis=1)
    seen = track + rng.normal(0.0, sigma, track.shape)
    h = k + 1  # last seen in frame 1, unseen for k frames, predicted into frame 2 + k
    extrapolated = seen[:, 1, None] + h[None, :, None] * (seen[:, 1] - seen[:, 0])[:, None]
    error = seen[:, 1 + h] - extrapolated  # (tracks, len(k), 3), the candidate's own noise included
    expected = TakeNoise(np.full(3, sigma), np.full(3, q)).prediction_sigma_mm(k)
    assert error.std(axis=0) == pytest.approx(expected, rel=0.03)
