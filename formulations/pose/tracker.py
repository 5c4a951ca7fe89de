"""Tracking frame after frame: the motion model's prediction, then one annealed search per frame.

Section 3.1: no motion model (each search starts from the previous estimate) or a damped
velocity model per DOF, X_pred = X_{k-1} + gamma (X_{k-1} - X_{k-2}) with 0 < gamma < 1. The
weighting function of a frame is the product of its measurements' (eq. 5 generalised:
w = exp(-sum of their energies)). A frame where no measurement saw anything is not searched:
the prediction is the estimate, and the frame is reported as unobserved.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from formulations.errors import FormulationError
from formulations.pose.apf import Annealed, AnnealingSchedule, anneal
from formulations.pose.body import TRANSLATION_DOF, BodyModel
from formulations.pose.kinematics import Posed, forward_kinematics
from formulations.pose.rotation import Array


class Measurement(Protocol):
    """A weighting function w(X, Z) = exp(-energy) of one frame's data Z."""

    @property
    def empty(self) -> bool: ...

    def energy(self, posed: Posed) -> Array: ...


def dispersion(model: BodyModel, translation: float, angle: float = 0.05) -> Array:
    """``(D,)`` first-layer dispersion: ``translation`` (model unit) for the root position, ``angle``
    radians for every joint angle; these must cover the frame-to-frame motion and a recoverable error."""
    spread = np.full(model.dof, angle)
    spread[:TRANSLATION_DOF] = translation
    return spread


@dataclass
class PoseTracker:
    """The model, the annealing schedule, the first-layer dispersion, the damping gamma (0: no motion
    model) and the seed; ``step`` one frame at a time from ``start``."""

    model: BodyModel
    start: Array
    spread: Array
    schedule: AnnealingSchedule = AnnealingSchedule()
    damping: float = 0.0
    seed: int = 0
    _history: list[Array] = field(default_factory=list, init=False)
    _rng: np.random.Generator = field(init=False)

    def __post_init__(self) -> None:
        if not 0.0 <= self.damping < 1.0:
            raise FormulationError(f"tracker: damping must be in [0, 1), got {self.damping}")
        if self.start.shape != (self.model.dof,) or self.spread.shape != (self.model.dof,):
            raise FormulationError(f"tracker: start and spread need {self.model.dof} values (the model's DOF)")
        self._rng = np.random.default_rng(self.seed)

    def prediction(self) -> Array:
        if not self._history:
            predicted: Array = self.model.clip(self.start[None])[0]
        elif len(self._history) == 1 or self.damping == 0.0:
            predicted = self._history[-1]
        else:
            predicted = self.model.clip((self._history[-1] + self.damping * (self._history[-1] - self._history[-2]))[None])[0]
        return predicted

    def step(self, measurements: Sequence[Measurement], layers: int | None = None, widen: float = 1.0) -> tuple[Array, bool]:
        """The estimate for the next frame and whether any measurement saw it; ``layers`` overrides the
        schedule's and ``widen`` multiplies the dispersion (a first frame searched from a rough start
        deserves both)."""
        predicted = self.prediction()
        live = [m for m in measurements if not m.empty]
        if not live:
            self._history.append(predicted)
            return predicted, False
        schedule = self.schedule if layers is None else AnnealingSchedule(
            self.schedule.particles, layers, self.schedule.survival, self.schedule.final_spread)
        result = self.search(live, predicted, schedule, self.spread * widen)
        self._history.append(result.estimate)
        return result.estimate, True

    def correct(self, estimate: Array) -> None:
        """Replace the last frame's estimate by a refinement of it: the next prediction starts there."""
        if not self._history:
            raise FormulationError("tracker: no frame has been estimated yet")
        self._history[-1] = self.model.clip(estimate[None])[0]

    def search(self, measurements: Sequence[Measurement], start: Array, schedule: AnnealingSchedule, spread: Array) -> Annealed:
        def energy(configurations: Array) -> Array:
            posed = forward_kinematics(self.model, configurations)
            total: Array = sum((m.energy(posed) for m in measurements), np.zeros(len(configurations)))
            return total

        return anneal(energy, start, spread, self.model.clip, schedule, self._rng)
