"""A box's return priced from the object's own last box: the pricing of skip arcs for boxes.

A skip arc (``formulations.window.skips``) joins box i of object n at frame m to box j at
frame m + k, the object unseen in between. Its re-entry term is the template term's for
boxes (``costs``), but with the forecast started from box i instead of the template:

    s(i, j) = a_pred (m^2 / 2 + log(det S_k / det R) / 2) + a_hist 0.5 ||hist(j) - hist(s_n)||_1,

m^2 the squared Mahalanobis distance of z(j) to z(i) + k v_n under S_k, the covariance of
the k-frame Kalman forecast (``kalman.predict``) from the state (z(i), v_n) with covariance
diag(R_i, P_vv): box i known to its measurement noise, the velocity v_n and its covariance
P_vv the object's at the template. R is the measurement noise at the predicted size, as in
the template term, so s and g(s_n, j) are in one unit and a box j seen where i's forecast
puts it costs what a box seen where the template's puts it does. Outside the gate
(m^2 > ``gate``) s is inf: no skip arc.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.boxes import kalman
from formulations.boxes.costs import BoxCostModel
from formulations.window.skips import SkipPricing

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


def reentry_pricing(mean: Array, covariance: Array, candidate_object: Ints, candidate_frame: Ints, boxes: Array,
                    appearance_cost: Array, model: BoxCostModel) -> SkipPricing:
    """The skip pricing s(i, j) of the module doc over one window's candidates.

    Args:
        mean, covariance: ``(N, 8)``, ``(N, 8, 8)`` the objects' Kalman states at the template.
        candidate_object, candidate_frame: ``(C,)`` object and window frame of each candidate.
        boxes: ``(C, 4)`` corners of each candidate.
        appearance_cost: ``(C,)`` the histogram part of each candidate's template term (0 without frames).
        model: Gate and weights.
    """
    z = kalman.measurement(boxes)

    def price(tail: Ints, head: Ints) -> Array:
        n, k = candidate_object[tail], candidate_frame[head] - candidate_frame[tail]
        state = np.concatenate([z[tail], mean[n, 4:]], axis=1)
        start = np.zeros((len(tail), 8, 8))
        start[:, :4, :4] = np.einsum("ni,ij->nij", (kalman.MEASUREMENT_SD * _size(z[tail])) ** 2, np.eye(4))
        start[:, 4:, 4:] = covariance[n, 4:, 4:]
        predicted, spread = np.zeros((len(tail), 4)), np.zeros((len(tail), 4, 4))
        for step in range(1, int(k.max(initial=0)) + 1):
            state, start = kalman.predict(state, start)
            now = k == step
            predicted[now], spread[now] = (part[now] for part in kalman.innovation(state, start))
        residual = z[head] - predicted
        squared = np.einsum("ni,ni->n", residual, np.linalg.solve(spread, residual[..., None])[..., 0])
        noise = (kalman.MEASUREMENT_SD * np.maximum(predicted[:, 2:], 1.0)) ** 2
        spread_log = np.linalg.slogdet(spread)[1] - 2.0 * np.log(noise).sum(axis=1)
        cost: Array = 0.5 * model.prediction * (squared + spread_log) + appearance_cost[head]
        cost[squared > model.gate] = np.inf
        return cost

    return price


def _size(z: Array) -> Array:
    """``(C, 4)`` the (w, h, w, h) the measurement noise of each box is proportional to."""
    wh = np.maximum(z[:, 2:], 1.0)
    result: Array = np.concatenate([wh, wh], axis=1)
    return result
