"""What a box candidate costs against its object: Jiang's template term g(s_n, v) for boxes.

For object n with Kalman prediction z_n(f), innovation covariance S_n(f) (``kalman``;
S grows with every frame since n was last seen) and a detection box v in frame f,

    g(s_n, v) = a_pred (m^2 / 2 + log(det S_n(f) / det R_n) / 2)
              + a_hist 0.5 ||hist(v) - hist(s_n)||_1        (only with frames),
    m^2 = (z(v) - z_n(f))^T S_n(f)^-1 (z(v) - z_n(f)),

the first line the negative log-likelihood of v's centre and size under the prediction,
less that of a box seen exactly where predicted one frame after its last sighting (R_n is
the measurement noise at the predicted size), so g >= 0 and a far-reaching prediction costs
both through its larger spread and the less it says; the second is the 64-bin grey
histogram of Jiang's examples (Sec. IV-A) against the template. A detection is a candidate
of n only inside the gate m^2 <= ``gate`` (a chi-square quantile, 4 degrees of freedom).

The arc costs of ``formulations.window.costs`` then add lambda_1 times the histogram change
between consecutive boxes and lambda_2 times d(i, j), the corner displacement between
consecutive boxes of the path off the object's velocity, in units of the object's height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.boxes import kalman

Array = NDArray[np.float64]


@dataclass(frozen=True)
class BoxCostModel:
    """Gate and costs of box candidates (see the module docstring).

    Attributes:
        gate: Largest squared Mahalanobis distance of a candidate to its prediction (30:
            chi-square with 4 degrees of freedom exceeds it once in 200,000; the tight 0.99
            quantile, 13.3, cuts people off where the camera turns).
        prediction: a_pred, weight of the negative log-likelihood under the prediction.
        histogram: a_hist, weight of the histogram distance to the template.
        histogram_change: lambda_1, weight of the histogram change between frames.
        displacement: lambda_2 per object height: weight of the corner displacement off the velocity.
        reappear: c_a, paid entering occlusion, the sink, or leaving occlusion.
        disappear: c_b, added entering occlusion or the sink.
        layout: mu per object height: weight of Jiang's L1 layout term between objects whose
            templates are within ``layout_reach`` heights (0: off); each object's
            displacement is in its own height, alike for neighbours at one depth.
        layout_reach: Template centre distance, in heights, under which two objects are neighbours.
        template_on_track: t, the factor of g(s_n, v) on arcs between two boxes (Jiang: 1;
            0 keeps it only where a box follows an occlusion, see ``formulations.window.costs``).
    """

    gate: float = 30.0
    prediction: float = 1.0
    histogram: float = 1.0
    histogram_change: float = 0.5
    displacement: float = 2.0
    reappear: float = 8.0
    disappear: float = 9.0
    layout: float = 0.0
    layout_reach: float = 1.5
    template_on_track: float = 1.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"box cost '{name}' must be finite and >= 0, got {value}")
        if self.gate <= 0:
            raise ValueError("box gate must be > 0")

    def gate_and_cost(self, predicted: Array, spread: Array, boxes: Array) -> tuple[NDArray[np.bool_], Array]:
        """Which boxes each prediction may take, and the prediction part of g for every pair.

        Args:
            predicted: ``(N, 4)`` predicted measurements z = (cx, cy, w, h).
            spread: ``(N, 4, 4)`` their innovation covariances S.
            boxes: ``(B, 4)`` corners of the frame's detections.

        Returns:
            ``(N, B)`` inside the gate, ``(N, B)`` a_pred (m^2 + log(det S / det R)) / 2.
        """
        squared = kalman.mahalanobis(kalman.measurement(boxes), predicted, spread)
        noise = (kalman.MEASUREMENT_SD * np.maximum(predicted[:, 2:], 1.0)) ** 2
        spread_log = np.linalg.slogdet(spread)[1] - 2.0 * np.log(noise).sum(axis=1)
        cost: Array = 0.5 * self.prediction * (squared + spread_log[:, None])
        return squared <= self.gate, cost


def histogram_distance(a: Array, b: Array) -> Array:
    """Half the L1 distance of normalised histograms, row by row: 0 same, 1 disjoint."""
    result: Array = 0.5 * np.abs(a - b).sum(axis=1)
    return result

