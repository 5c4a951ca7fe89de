"""Arc costs of the window network: Jiang, Fels & Little (2008), Sec. II-B.

For object n, an arc from node i (frame m) to node j (frame m+1) costs

    c(i, j) = t g(s_n, j) + lambda_1 g(i, j) + lambda_2 d(i, j) i, j observations
            = c_a + g(s_n, j)                                    i occlusion, j observation
            = c_a + c_b                                          j occlusion or sink

where t = 1 in Jiang's paper (``template_on_track``; the marker chains set their own, with
what it was measured against), g compares appearances (here: half the L1 distance of
normalised histograms, in [0, 1]) and g(s_n, j) is supplied per candidate by the candidate
generator (it is the template term: appearance to the template; for markers the shape
signature in a 3D cloud, the distance to the prediction per camera). d is the displacement
off the expected motion of the object,

    d(i, j) = || r_j - r_i - delta_n(m+1) ||_2,

which is Jiang's plain distance when the expected displacement delta is zero (boxes) and
a constant-velocity residual when delta is a velocity estimate (markers). Where delta is
unknown (NaN: a marker seen in one frame only) the d term is left out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.window.problem import OBSERVATION, OCCLUSION, SINK, SOURCE


@dataclass(frozen=True)
class ArcCostWeights:
    """Weights of Jiang's three-case arc cost.

    Attributes:
        appearance_change: lambda_1, weight of g(i, j) between consecutive observations.
        displacement: lambda_2, weight of d(i, j) (per unit of location, e.g. per mm).
        reappear: c_a, constant paid on entering occlusion, the sink, or leaving occlusion.
        disappear: c_b, constant added on entering occlusion or the sink.
        template_on_track: t, factor of g(s_n, j) on observation-to-observation arcs.
    """

    appearance_change: float = 0.0
    displacement: float = 1.0
    reappear: float = 10.0
    disappear: float = 10.0
    template_on_track: float = 1.0

    def __post_init__(self) -> None:
        for name in ("appearance_change", "displacement", "reappear", "disappear", "template_on_track"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise ValueError(f"arc cost weight '{name}' must be finite and >= 0, got {value}")


def arc_costs(
    weights: ArcCostWeights,
    tail: np.ndarray,
    head: np.ndarray,
    kind: np.ndarray,
    location: np.ndarray,
    template_cost: np.ndarray,
    motion: np.ndarray,
    appearance_change: np.ndarray | None,
    source_occluded: np.ndarray,
) -> np.ndarray:
    """Cost of every arc, vectorised over arcs.

    Args:
        weights: The cost weights.
        tail, head: ``(A,)`` node indices of each arc.
        kind: ``(V,)`` node kinds.
        location: ``(V, D)`` node locations.
        template_cost: ``(V,)`` g(s_n, v) per node (0 where not an observation).
        motion: ``(V, D)`` expected displacement into each node's frame (NaN: unknown).
        appearance_change: ``(A,)`` g(tail, head) per arc, or None when there is no appearance.
        source_occluded: ``(V,)`` True for sources whose template is not visible: their
            out-arcs cost like arcs out of an occlusion node.

    Returns:
        ``(A,)`` arc costs.
    """
    c_ab = weights.reappear + weights.disappear
    tail_kind, head_kind = kind[tail], kind[head]
    into_gap = (head_kind == OCCLUSION) | (head_kind == SINK)
    from_gap = (tail_kind == OCCLUSION) | ((tail_kind == SOURCE) & source_occluded[tail])
    observed = (head_kind == OBSERVATION) & ~from_gap

    cost = np.full(len(tail), float(c_ab))  # integer weights must not make integer costs
    reappearing = (head_kind == OBSERVATION) & from_gap
    cost[reappearing] = weights.reappear + template_cost[head[reappearing]]

    t, h = tail[observed], head[observed]
    # np.take gathers the same rows several times faster than fancy indexing of (V, D) arrays
    step = np.take(location, h, axis=0) - np.take(location, t, axis=0) - np.take(motion, h, axis=0)
    distance = np.nan_to_num(np.sqrt(np.einsum("ad,ad->a", step, step)), nan=0.0)
    cost_obs = weights.template_on_track * template_cost[h] + weights.displacement * distance
    if appearance_change is not None and weights.appearance_change > 0:
        cost_obs += weights.appearance_change * appearance_change[observed]
    cost[observed] = cost_obs
    cost[into_gap] = c_ab
    return cost
