"""Arc costs as negative log-likelihoods (Ringer & Lasenby 2002, eq. 10, in spirit).

Jiang's constants c_a, c_b and lambda_2 weigh a step against an occlusion by hand. Here an
object's path through frame m pays the negative log-likelihood of what its node says
happened, against the same data explained without it:

    observation j after an observation i:   rho(|d(i, j)| / s) + o_j
    observation j after a gap (reappear):   r_j   (the candidate's own, from its prediction)
    occlusion in frame m:                   -log(1 - P_D) + K

with d(i, j) = r_j - r_i - delta as in ``costs``, s the sd per axis of that residual,
o_j = 3 log s + (3/2) log 2 pi - log P_D + log lambda_FA + K the rest of a 3D Gaussian's
log density against the point being a false alarm of density lambda_FA (per mm^3), and K
one shift per window that keeps every cost >= 0 (every path crosses each frame once, so K
changes no comparison). rho is the negative log density of a contaminated Gaussian: with
probability 1 - eps the residual is N(0, s^2) per axis, with eps a burst N(0, (k s)^2),
because real accelerations come in bursts a Gaussian would call impossible. The
candidate generator supplies s, o, r and the occlusion costs (``CandidateLikelihood``);
the template term g(s_n, j) is added to every arc into j, times t after an observation
(as in ``costs``) and whole after a gap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.window.problem import OBSERVATION, OCCLUSION, SOURCE

# A share of steps are bursts ten times wider than the learned sd (an impact, a spike in a
# gap-filled export): a Gaussian alone would call them impossible and drop the marker.
# Chosen against Huber's loss on the tuning half of the accuracy matrix and three real
# relabellings (Qualisys, CMU 135_02, tennis), not on the validation half.
BURST_SHARE = 0.01  # eps
BURST_WIDTH = 10.0  # k


@dataclass(frozen=True)
class CandidateLikelihood:
    """What the likelihood costs need, per candidate and per (object, frame).

    Attributes:
        step_sigma: ``(C,)`` s, sd per axis of the step residual into the candidate (mm).
        step_offset: ``(C,)`` o_j (module doc).
        reappear_cost: ``(C,)`` whole cost of entering the candidate after a gap, or where
            the step residual is unknown.
        miss_cost: ``(N, M)`` cost of each occlusion node.
    """

    step_sigma: np.ndarray
    step_offset: np.ndarray
    reappear_cost: np.ndarray
    miss_cost: np.ndarray


def step_loss(z: np.ndarray) -> np.ndarray:
    """rho(z): the negative log density of a residual z sds off, relative to z = 0, under a
    contaminated Gaussian (module doc):

        rho(z) = -log[((1 - eps) e^(-z^2 / 2) + eps k^-3 e^(-z^2 / (2 k^2))) / (1 - eps + eps k^-3)].
    """
    core = np.log1p(-BURST_SHARE) - 0.5 * z**2
    burst = np.log(BURST_SHARE) - 3 * np.log(BURST_WIDTH) - 0.5 * (z / BURST_WIDTH) ** 2
    at_zero = np.logaddexp(np.log1p(-BURST_SHARE), np.log(BURST_SHARE) - 3 * np.log(BURST_WIDTH))
    rho: np.ndarray = at_zero - np.logaddexp(core, burst)
    return rho


def likelihood_arc_costs(
    template_on_track: float, node_likelihood: dict[str, np.ndarray], tail: np.ndarray, head: np.ndarray, kind: np.ndarray,
    location: np.ndarray, template_cost: np.ndarray, motion: np.ndarray, source_occluded: np.ndarray,
) -> np.ndarray:
    """Cost of every arc (module doc), vectorised over arcs.

    Args:
        template_on_track: t, the factor of g(s_n, j) on an observation-to-observation arc
            (1 on arcs out of a gap, where the template term is all that ties j to n).
        node_likelihood: Per node ``step_sigma``, ``step_offset``, ``reappear_cost`` (read at
            observation nodes) and ``miss_cost`` (read at occlusion nodes).
        Others: as ``costs.arc_costs``.
    """
    # What depends on one node only is worked out per node and gathered once per arc.
    gap = (kind == OCCLUSION) | ((kind == SOURCE) & source_occluded)  # a path out of it re-enters after a gap
    is_observation = kind == OBSERVATION
    # Cost of entering a node: the whole of an occlusion's, an observation's after a gap (a
    # step replaces it below), nothing for a sink.
    entry = np.zeros(len(kind))
    entry[kind == OCCLUSION] = node_likelihood["miss_cost"][kind == OCCLUSION]
    entry[is_observation] = node_likelihood["reappear_cost"][is_observation]
    cost: np.ndarray = entry[head]
    into_observation = np.flatnonzero(is_observation[head])
    observed = ~gap[tail[into_observation]]
    t, h = tail[into_observation[observed]], head[into_observation[observed]]
    # np.take gathers the same rows several times faster than fancy indexing of (V, D) arrays
    step = np.take(location, h, axis=0) - np.take(location, t, axis=0) - np.take(motion, h, axis=0)
    z = np.sqrt(np.einsum("ad,ad->a", step, step)) / node_likelihood["step_sigma"][h]
    known = np.isfinite(z)
    cost[into_observation[observed][known]] = step_loss(z[known]) + node_likelihood["step_offset"][h[known]]
    cost[into_observation] += np.where(observed, template_on_track, 1.0) * template_cost[head[into_observation]]
    return cost
