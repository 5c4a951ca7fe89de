"""What a box candidate costs against its object: Jiang's template term g(s_n, v) for boxes.

For object n with prediction p (corners, height h_p) and a detection box v in frame m,

    g(s_n, v) = a_pred ||centre(v) - centre(p)|| / (h_p gap)
              + a_shape (|log w_v / w_n| + |log h_v / h_n|)
              + a_hist  0.5 ||hist(v) - hist(s_n)||_1        (only with frames),

the shape and the 64-bin grey histogram of Jiang's examples (Sec. IV-A), measured against
the template s_n (the object's last seen box), plus the distance to the prediction, in
predicted heights so that near and far people weigh the same, and per frame of
extrapolation (gap: frames since n was last seen), since a constant-velocity prediction
drifts with every frame it reaches ahead (a moving camera pans, people turn). The arc cost of
``formulations.window.costs`` adds lambda_1 times the histogram change between consecutive
boxes and lambda_2 times the corner displacement off the object's velocity.

A detection is a candidate of n only inside the gate

    ||centre(v) - centre(p)|| <= h_p min(reach + reach_growth (gap - 1), reach_max),
    1 / size_ratio <= h_v / h_p <= size_ratio,

with the same gap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.boxes.geometry import centre, height

Array = NDArray[np.float64]


@dataclass(frozen=True)
class BoxCostModel:
    """Gate and costs of box candidates, in units of box heights (see the module docstring).

    Attributes:
        reach: Gate radius, in predicted heights, one frame after the object was seen.
        reach_growth: Added to the radius per further frame unseen.
        reach_max: Largest gate radius, in predicted heights.
        size_ratio: Largest height ratio of a candidate to its prediction.
        prediction: a_pred, weight of the distance to the prediction.
        shape: a_shape, weight of the log width and height ratios to the template.
        histogram: a_hist, weight of the histogram distance to the template.
        histogram_change: lambda_1, weight of the histogram change between frames.
        displacement: lambda_2 times the median box height of the sequence: weight of the
            corner displacement off the velocity, per median height.
        reappear: c_a, paid entering occlusion, the sink, or leaving occlusion.
        disappear: c_b, added entering occlusion or the sink.
        layout: mu times the median box height: weight of Jiang's L1 layout term between
            objects whose templates are within ``layout_reach`` heights (0: off).
        layout_reach: Template centre distance, in heights, under which two objects are neighbours.
        template_on_track: t, the factor of g(s_n, v) on arcs between two boxes (Jiang: 1;
            0 keeps it only where a box follows an occlusion, see ``formulations.window.costs``).
    """

    reach: float = 0.5
    reach_growth: float = 0.1
    reach_max: float = 2.0
    size_ratio: float = 1.6
    prediction: float = 1.0
    shape: float = 1.0
    histogram: float = 1.0
    histogram_change: float = 0.5
    displacement: float = 2.0
    reappear: float = 0.5
    disappear: float = 0.5
    layout: float = 0.0
    layout_reach: float = 1.5
    template_on_track: float = 1.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"box cost '{name}' must be finite and >= 0, got {value}")
        if self.size_ratio < 1 or self.reach <= 0:
            raise ValueError("box gate: size_ratio must be >= 1 and reach > 0")

    def gate(self, predicted: Array, gap: Array, boxes: Array) -> tuple[NDArray[np.bool_], Array]:
        """Which boxes each prediction may take, and their distance to it in predicted heights.

        Args:
            predicted: ``(N, 4)`` predicted corners.
            gap: ``(N,)`` frames since each object was seen (>= 1).
            boxes: ``(B, 4)`` corners of the frame's detections.

        Returns:
            ``(N, B)`` inside the gate, ``(N, B)`` normalised centre distance.
        """
        h = np.maximum(height(predicted), 1.0)
        distance = np.linalg.norm(centre(boxes)[None] - centre(predicted)[:, None], axis=2) / h[:, None]
        radius = np.minimum(self.reach + self.reach_growth * (gap - 1), self.reach_max)
        ratio = height(boxes)[None] / h[:, None]
        # gap < 1: a frame before the object's birth, where it has nothing to take
        inside = (distance <= radius[:, None]) & (ratio <= self.size_ratio) & (ratio >= 1.0 / self.size_ratio)
        inside &= (gap >= 1)[:, None]
        return inside, distance

    def template_cost(self, distance: Array, gap: Array, template: Array, boxes: Array,
                      histogram_distance: Array | None) -> Array:
        """g(s_n, v) per (object, box) pair, given arrays aligned pair by pair."""
        size = np.maximum(boxes[:, 2:] - boxes[:, :2], 1.0)
        size_t = np.maximum(template[:, 2:] - template[:, :2], 1.0)
        cost: Array = self.prediction * distance / gap + self.shape * np.abs(np.log(size / size_t)).sum(axis=1)
        if histogram_distance is not None:
            cost = cost + self.histogram * histogram_distance
        return cost


def histogram_distance(a: Array, b: Array) -> Array:
    """Half the L1 distance of normalised histograms, row by row: 0 same, 1 disjoint."""
    result: Array = 0.5 * np.abs(a - b).sum(axis=1)
    return result
