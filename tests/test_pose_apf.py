"""The annealed particle filter: the annealing rate, the paper's argument for layers, limits, seeding."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.errors import FormulationError
from formulations.pose.apf import AnnealingSchedule, anneal, annealing_rate
from formulations.pose.human import human_model
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.tracker import PoseTracker, dispersion

PEAK = np.array([1.3, -2.1])


def bumpy(X: np.ndarray) -> np.ndarray:
    """A smooth bowl around PEAK with a local minimum of the energy (maximum of w) every unit apart."""
    Y = X - PEAK
    return (Y ** 2).sum(axis=1) / 2 + 2.0 * (2 - np.cos(2 * np.pi * Y[:, 0]) - np.cos(2 * np.pi * Y[:, 1]))


def test_annealing_rate_gives_the_target_survival_rate() -> None:
    energies = np.random.default_rng(0).gamma(2.0, 3.0, 400)
    for target in (0.2, 0.5, 0.8):
        beta = annealing_rate(energies, target)
        w = np.exp(-beta * (energies - energies.min()))
        survival = w.sum() ** 2 / (w ** 2).sum() / len(w)
        assert abs(survival - target) < 1e-3


def test_layers_find_the_global_maximum_where_one_layer_of_as_many_evaluations_does_not() -> None:
    def found(particles: int, layers: int) -> float:
        hits = []
        for seed in range(20):
            result = anneal(bumpy, np.zeros(2), np.full(2, 3.0), lambda X: np.clip(X, -5, 5),
                            AnnealingSchedule(particles, layers), np.random.default_rng(seed))
            hits.append(np.linalg.norm(result.estimate - PEAK) < 0.3)  # inside the global peak's basin
        return float(np.mean(hits))

    annealed, single = found(100, 10), found(1000, 1)
    assert annealed >= 0.8 and single <= 0.2, (annealed, single)


def test_joint_limits_are_never_violated_even_when_the_data_pull_beyond_them() -> None:
    model = human_model()
    knee = model.columns[model.index("RKnee")]
    elbow = model.columns[model.index("LElbow")]

    def beyond(X: np.ndarray) -> np.ndarray:  # wants a hyper-extended knee and elbow
        return (X[:, knee] + 1.0) ** 2 + (X[:, elbow] - 1.0) ** 2

    result = anneal(beyond, np.zeros(model.dof), np.full(model.dof, 0.5), model.clip, AnnealingSchedule(200, 8),
                    np.random.default_rng(3))
    for X in (result.particles, result.estimate[None]):
        assert (model.lower - 1e-12 <= X).all() and (model.upper + 1e-12 >= X).all()
    assert abs(result.estimate[knee]) < 0.05 and abs(result.estimate[elbow]) < 0.05  # pinned at the limits


def test_the_same_seed_gives_the_same_estimate() -> None:
    model = human_model()
    target = forward_kinematics(model, np.zeros((1, model.dof))).positions

    def energy(X: np.ndarray) -> np.ndarray:
        return ((forward_kinematics(model, X).positions - target) ** 2).sum(axis=(1, 2))

    runs = [anneal(energy, np.full(model.dof, 0.1), np.full(model.dof, 0.1), model.clip, AnnealingSchedule(50, 3),
                   np.random.default_rng(seed)).estimate for seed in (7, 7, 8)]
    assert np.array_equal(runs[0], runs[1]) and not np.array_equal(runs[0], runs[2])


class _Nothing:
    """A frame where the measurement saw nothing."""

    empty = True

    def energy(self, posed: object) -> np.ndarray:
        raise AssertionError("an empty measurement is not searched")


class _Towards:
    """Pulls the root towards a target position."""

    empty = False

    def __init__(self, target: np.ndarray) -> None:
        self.target = target

    def energy(self, posed) -> np.ndarray:
        return ((posed.positions[:, 0] - self.target) ** 2).sum(axis=1)


def test_damped_velocity_predicts_and_a_frame_without_data_keeps_the_prediction() -> None:
    model = human_model()
    tracker = PoseTracker(model, np.zeros(model.dof), dispersion(model, 0.05, 0.01), AnnealingSchedule(100, 6), damping=0.5)
    first, seen = tracker.step([_Towards(np.array([0.0, 0.0, 0.0]))])
    second, _ = tracker.step([_Towards(np.array([0.05, 0.0, 0.0]))])  # within the dispersion
    assert seen and abs(second[0] - 0.05) < 0.01
    third, seen = tracker.step([_Nothing()])
    assert not seen and np.allclose(third, model.clip((second + 0.5 * (second - first))[None])[0])


def test_a_corrected_estimate_is_what_the_next_frame_starts_from() -> None:
    model = human_model()
    tracker = PoseTracker(model, np.zeros(model.dof), dispersion(model, 0.05, 0.01), AnnealingSchedule(50, 2))
    with pytest.raises(FormulationError):
        tracker.correct(np.zeros(model.dof))
    tracker.step([_Towards(np.zeros(3))])
    polished = np.zeros(model.dof)
    polished[0] = 0.2
    polished[model.columns[model.index("RKnee")]] = -1.0  # beyond the knee's limit: clipped to 0
    tracker.correct(polished)
    expected = polished.copy()
    expected[model.columns[model.index("RKnee")]] = 0.0
    assert np.array_equal(tracker.prediction(), expected)
