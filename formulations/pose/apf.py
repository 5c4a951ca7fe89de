"""The annealed particle filter (Deutscher, Blake & Reid 2000; Davison et al. 2001, Fig. 4).

One time step searches for the configuration maximising w(X, Z) = exp(-E(X, Z)) with M layers
of N particles. Layer m (m = M, ..., 1) weights every particle s by

    pi_m(s) proportional to w(X = s, Z)^beta_m = exp(-beta_m E(s)),

where beta_m, the annealing rate, is chosen so that the particle survival rate

    alpha = D / N,   D = 1 / sum_n pi_n^2          (MacCormick & Blake's survival diagnostic)

equals the target alpha: a small beta flattens the weights (alpha -> 1, a coarse search), a
large one sharpens them. Unless it is the last layer, the set is resampled by weight and
dispersed by Gaussian noise of covariance B_{m-1}, which shrinks geometrically from layer to
layer (B_m = rho^(2(M - m)) B_M, rho chosen so the last layer's spread is ``final_spread`` of
the first), then clipped onto the joint limits. The output is the weighted mean of the last
layer's set: a tight cluster around the global maximum, not a posterior.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from formulations.errors import FormulationError
from formulations.pose.rotation import Array

# Deutscher et al. ran a few hundred particles; each holds a configuration and its projections in
# every camera, so 10^8 asked for 25 GiB before the first frame (a MemoryError, not a message).
MAX_PARTICLES = 100_000
MAX_LAYERS = 1_000  # time grows with them: a thousand layers per frame is already hours per take
Energy = Callable[[Array], Array]  # (N, D) configurations -> (N,) energies E >= 0, w = exp(-E)
Clip = Callable[[Array], Array]  # (N, D) -> (N, D) onto the joint limits


@dataclass(frozen=True)
class AnnealingSchedule:
    """M layers of N particles, the target survival rate alpha, and how much the dispersion shrinks."""

    particles: int = 300
    layers: int = 10
    survival: float = 0.5
    final_spread: float = 0.1

    def __post_init__(self) -> None:
        if not (2 <= self.particles <= MAX_PARTICLES and 1 <= self.layers <= MAX_LAYERS):
            raise FormulationError(f"apf: needs 2 to {MAX_PARTICLES:,} particles and 1 to {MAX_LAYERS} layers, "
                                   f"got {self.particles} and {self.layers}")
        if not 0.0 < self.survival < 1.0 or not 0.0 < self.final_spread <= 1.0:
            raise FormulationError("apf: survival rate must be in (0, 1) and final_spread in (0, 1]")

    def spread(self, layer: int) -> float:
        """The dispersion's standard deviation at layer ``layer`` (0 first) relative to the first's."""
        return float(self.final_spread ** (layer / max(self.layers - 1, 1)))


@dataclass(frozen=True)
class Annealed:
    """The estimate, the last layer's particles and weights, and the annealing rate of each layer."""

    estimate: Array
    particles: Array
    weights: Array
    rates: Array


def annealing_rate(energies: Array, survival: float, iterations: int = 60) -> float:
    """The beta with D(beta) / N = ``survival`` (module doc), by bisection on log beta.

    alpha(beta) falls monotonically from 1 at beta = 0; if no beta reaches the target (all
    energies equal) the weights are uniform whatever beta is, and beta = 1 is returned.
    """
    spread = energies - energies.min()
    if not np.isfinite(spread).all():
        raise FormulationError("apf: the weighting function returned a non-finite energy")
    if spread.max() <= 0.0:
        return 1.0
    low, high = -30.0, 30.0  # log beta, relative to the energies' own scale below
    scale = 1.0 / float(np.median(spread[spread > 0]))
    for _ in range(iterations):
        middle = 0.5 * (low + high)
        weights = np.exp(-np.exp(middle) * scale * spread)
        if weights.sum() ** 2 / (weights ** 2).sum() / len(weights) > survival:
            low = middle
        else:
            high = middle
    return float(np.exp(0.5 * (low + high)) * scale)


def _weights(energies: Array, rate: float) -> Array:
    weights = np.exp(-rate * (energies - energies.min()))
    normalised: Array = weights / weights.sum()
    return normalised


def _systematic_resample(weights: Array, rng: np.random.Generator) -> Array:
    """Indices of N particles drawn by weight with one uniform offset (low-variance resampling)."""
    positions = (rng.random() + np.arange(len(weights))) / len(weights)
    indices: Array = np.minimum(np.searchsorted(np.cumsum(weights), positions), len(weights) - 1)
    return indices


def anneal(energy: Energy, start: Array, spread: Array, clip: Clip, schedule: AnnealingSchedule,
           rng: np.random.Generator) -> Annealed:
    """One time step of Fig. 4 from ``start`` (D,) (the motion model's prediction), dispersing the
    first layer by ``spread`` (D,) standard deviations."""
    dimension = len(start)
    particles = clip(start + rng.normal(size=(schedule.particles, dimension)) * spread)
    rates = []
    for layer in range(schedule.layers):
        energies = energy(particles)
        rates.append(annealing_rate(energies, schedule.survival))
        weights = _weights(energies, rates[-1])
        if layer == schedule.layers - 1:
            break
        chosen = particles[_systematic_resample(weights, rng)]
        noise = rng.normal(size=chosen.shape) * spread * schedule.spread(layer + 1)
        particles = clip(chosen + noise)
    estimate: Array = weights @ particles
    return Annealed(estimate, particles, weights, np.array(rates))
