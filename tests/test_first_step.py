"""The first step after a labeled frame, by minimum acceleration (``markers.first_step``)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import formulations.markers.first_step as first_step
import formulations.markers.guide as guide
from formulations.markers.first_step import coherent_steps, first_velocities
from service import Capture, CaptureLabeling
from service.evaluation.scenario import Scenario
from service.evaluation.scene import generate_scene
from service.evaluation.simulate_cloud import simulate_cloud

REACH = 200.0


def _acceleration(position: np.ndarray, following: np.ndarray, after: np.ndarray, i: int, j: int) -> float:
    """Marker i taking point j: distance from 2 x_j - p_i to the nearest point of the frame after."""
    extrapolated = 2 * following[j] - position[i]
    return min(float(np.linalg.norm(q - extrapolated)) for q in after)


def _miss(position: np.ndarray, following: np.ndarray, after: np.ndarray) -> float:
    """Three times the median over markers of their least acceleration to a reachable point."""
    least = [
        min((_acceleration(position, following, after, i, j) for j in range(len(following))
             if np.linalg.norm(following[j] - position[i]) <= REACH), default=np.inf)
        for i in range(len(position))
    ]
    return 3.0 * max(float(np.median([a for a in least if np.isfinite(a)])), 1.0 / 3.0)


def _cost(position: np.ndarray, following: np.ndarray, after: np.ndarray, taken: list[int | None]) -> float:
    """sum over markers of the acceleration at the frame after, a miss at ``_miss``, written out."""
    miss = _miss(position, following, after)
    return sum(miss if j is None else _acceleration(position, following, after, i, j) for i, j in enumerate(taken))


def _brute_force(position: np.ndarray, following: np.ndarray, after: np.ndarray) -> float:
    """The least cost over every one-to-one choice of a reachable point or none per marker."""
    k, p = len(position), len(following)
    best = np.inf
    for choice in itertools.product([None, *range(p)], repeat=k):
        taken = [j for j in choice if j is not None]
        if len(set(taken)) < len(taken):
            continue
        if any(j is not None and np.linalg.norm(following[j] - position[i]) > REACH for i, j in enumerate(choice)):
            continue
        best = min(best, _cost(position, following, after, list(choice)))
    return best


@pytest.mark.parametrize("seed", range(12))
def test_first_step_is_the_least_acceleration_matching(seed: int):
    rng = np.random.default_rng(seed)
    position = rng.uniform(0, 300, (3, 3))
    following = np.concatenate([position + rng.normal(0, 60, (3, 3)), rng.uniform(0, 300, (2, 3))])
    after = np.concatenate([2 * following[:3] - position + rng.normal(0, 20, (3, 3)), rng.uniform(0, 300, (3, 3))])
    velocity = first_velocities(position, following, after, REACH)
    taken: list[int | None] = []
    for i in range(3):
        match = np.flatnonzero(np.linalg.norm(following - (position[i] + velocity[i]), axis=1) < 1e-9)
        taken.append(int(match[0]) if len(match) else None)
    assert _cost(position, following, after, taken) == pytest.approx(_brute_force(position, following, after))


def _racing_start() -> tuple[np.ndarray, list[np.ndarray]]:
    """A glove of three markers 30 mm apart and a trunk of four, all travelling 90 mm a frame
    at 70 Hz from the labeled frame on; the glove's own point is farther from where it was
    than a neighbour's is."""
    glove = 30.0 * np.array([[0.0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
    trunk = np.array([[0.0, 300, 200], [150, 300, 200], [0, 450, 200], [150, 450, 350]])
    body = np.concatenate([glove, trunk])
    travel = np.arange(40)[:, None, None] * np.array([77.0, 46.0, 0.0])  # 90 mm a frame
    truth = body[None] + travel
    noisy = truth + np.random.default_rng(3).normal(0.0, 0.5, truth.shape)
    return noisy, list(noisy)


def _mislabeled_frames() -> list[int]:
    noisy, points = _racing_start()
    names = [f"m{i}" for i in range(noisy.shape[1])]
    labels, _ = CaptureLabeling(Capture(names, noisy[0], 70.0, points=points)).label()
    own = np.arange(noisy.shape[1])
    return [f for f in range(len(points)) if (labels.point_index[f] != own).any()]


def test_a_subject_already_moving_keeps_its_labels_from_the_first_step():
    wrong = _mislabeled_frames()
    assert not wrong, f"{len(wrong)} frames mislabeled from frame {wrong[0]}"


def test_without_the_first_step_the_moving_start_is_mislabeled(monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setattr(guide, "_moving_start", lambda state, frames, gate: state)
    wrong = _mislabeled_frames()
    assert wrong and wrong[0] == 1


def test_a_marker_deleted_next_frame_is_not_sent_after_a_ghost():
    """A still subject; marker 0's point is missing from the next frame, where a ghost lies
    60 mm off it, and a ghost of the frame after lies 40 mm from where that step leads.
    40 mm of acceleration is within the reach but far beyond the subject's, so marker 0
    takes nothing and stays where it was (the whole reach as miss cost took the ghost)."""
    rng = np.random.default_rng(5)
    position = rng.uniform(0, 400, (8, 3))
    following = np.concatenate([position[1:], position[:1] + [60.0, 0, 0]]) + rng.normal(0, 0.5, (8, 3))
    after = np.concatenate([position, position[:1] + [120.0, 40.0, 0]]) + rng.normal(0, 0.5, (9, 3))
    velocity = first_velocities(position, following, after, REACH)
    assert np.linalg.norm(velocity, axis=1).max() < 3.0


@pytest.mark.parametrize("seed", [3, 5, 21])
def test_in_heavy_clutter_only_steps_shared_with_neighbours_are_kept(seed: int, monkeypatch: pytest.MonkeyPatch):
    """A walker (about 12 mm a frame) under 10 mm noise, 10 % deleted and 100 ghosts a frame:
    some ghost pair always lines up, so minimum acceleration alone sends a marker several
    times farther off its true step than starting still would; keeping only the steps the
    neighbours share (after the matching that prices departing from them) does not."""
    truth = generate_scene(n_frames=20, seed=seed)
    clutter = Scenario(noise_mm=10.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=100.0, seed=seed)
    cloud = simulate_cloud(truth, clutter).cloud
    start, true_step = truth.positions[0], truth.positions[1] - truth.positions[0]
    monkeypatch.setattr(first_step, "SHARED_ROUNDS", 0)
    least_acceleration = first_velocities(start, cloud.points[1], cloud.points[2], REACH)
    monkeypatch.undo()
    matched = first_velocities(start, cloud.points[1], cloud.points[2], REACH)

    def error(velocity: np.ndarray) -> float:  # the worst marker's: one gross error mislabels
        return float(np.linalg.norm(velocity - true_step, axis=1).max())

    still = error(np.zeros_like(true_step))
    assert error(least_acceleration) > 2 * still
    assert error(coherent_steps(start, matched)) <= 1.2 * still


def _turning_glove(seed: int) -> list[np.ndarray]:
    """Frames 0-2 of a glove (three markers 30 mm apart) turning up to 0.6 rad a frame while it
    travels 70-95 mm a frame with its own acceleration, beside five body markers travelling
    with it; 1.5 mm noise."""
    rng = np.random.default_rng(seed)
    glove = 30.0 * np.array([[0.0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
    glove = Rotation.random(random_state=seed).apply(glove - glove.mean(axis=0))
    body = rng.uniform(-250, 250, (5, 3))
    body[np.linalg.norm(body, axis=1) < 120] *= 2
    travel = rng.normal(size=3)
    travel *= rng.uniform(70, 95) / np.linalg.norm(travel)
    acceleration = rng.normal(0, 8, 3)
    turn = Rotation.from_rotvec(rng.normal(size=3) / np.sqrt(3) * rng.uniform(0, 0.6))
    frames, turned = [], glove
    for t in range(3):
        frames.append(np.concatenate([turned + travel * t + acceleration * t * t / 2, body + travel * t]))
        turned = turn.apply(turned)
    return [frame + rng.normal(0, 1.5, frame.shape) for frame in frames]


def _not_own_steps(frames: list[np.ndarray]) -> int:
    """Markers whose first step does not lead to their own point of the next frame."""
    velocity = first_velocities(frames[0], frames[1], frames[2], REACH)
    landed = np.linalg.norm(frames[1][None] - (frames[0] + velocity)[:, None], axis=2).argmin(axis=1)
    return int(((landed != np.arange(len(frames[0]))) | ~velocity.any(axis=1)).sum())


def test_a_turning_glove_keeps_its_steps_by_the_step_its_neighbours_share(monkeypatch: pytest.MonkeyPatch):
    """Minimum acceleration alone sends glove markers onto their mates' points; the matching
    made again with each step's departure from its neighbours' median step sends fewer, and
    in no scene more."""
    scenes = [_turning_glove(seed) for seed in range(100)]
    monkeypatch.setattr(first_step, "SHARED_ROUNDS", 0)
    alone = [_not_own_steps(frames) for frames in scenes]
    monkeypatch.undo()
    shared = [_not_own_steps(frames) for frames in scenes]
    assert sum(alone) >= 15
    assert sum(shared) <= sum(alone) / 3
    assert all(s <= a for s, a in zip(shared, alone, strict=True))
