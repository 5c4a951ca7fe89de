"""Which lost marker a returning point belongs to, judged as the window judges a return.

The guide (``guide``) assigns points by distance in mm. Between two lost markers gated on one
returning point, that favours the one predicted nearer, whatever each prediction's spread
(03_rolling under the issue's scenario, seed 1, frame 315: LL_USP, lost 17 frames, 57 mm off,
took LL_RSP's point from LL_RSP, lost 131 frames, 73 mm off). The window prices a return by
the prediction's spread (``markers.likelihood``), s_u^2 = s_n^2 + g^2 u per axis, u frames
unseen:

    r_n(x) = rho(|x - p_n| / s_u) + 3 log s_u,

and there LL_RSP's return cost 11.1 against LL_USP's 15.8. But the window follows the guide's
track: the later frames of the guide's marker are priced as steps (0.8-1.3), the other's as
returns from its stale prediction (10.9-12.2 a frame), so the window kept the guide's choice
with a sure margin, and LL_USP held LL_RSP's point to the end of the take.

Here a point the guide gave a lost marker goes to another lost marker that the guide left
without a point, whose gate holds it, and whose return cost is lower by at least
``MARGIN_NATS``. Only returns are judged: a marker seen the frame before keeps what the
nearest-neighbour assignment gave it.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from formulations.markers.state import MarkerState
from formulations.window.likelihood import step_loss

MARGIN_NATS = 1.0  # a return cost lower by less is a tie, and the guide's nearest pick stands


def return_costs(state: MarkerState, predicted: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(N, P)`` r_n(x_p) of the module doc for every marker and point."""
    sigma = np.sqrt(state.prediction_var(state.unseen))[:, None]
    cost: np.ndarray = step_loss(cdist(predicted, points) / sigma) + 3 * np.log(sigma)
    return cost


def returns_judged(
    state: MarkerState, predicted: np.ndarray, points: np.ndarray, assigned: np.ndarray, radius: np.ndarray,
) -> np.ndarray:
    """``assigned`` (``(N,)`` point per marker, -1 none) with each returning point given to the
    lost marker of lowest return cost (module doc), one point at a time, cheapest gain first."""
    lost = ~state.visible
    returning = np.flatnonzero(lost & (assigned >= 0))
    if len(returning) == 0 or not (lost & (assigned < 0)).any():
        return assigned
    out = assigned.copy()
    within = cdist(predicted, points) <= radius[:, None]
    cost = return_costs(state, predicted, points)
    for n in returning[np.argsort(cost[returning, assigned[returning]])[::-1]]:
        p = out[n]
        free = np.flatnonzero(lost & (out < 0) & within[:, p])
        if len(free) == 0:
            continue
        best = free[np.argmin(cost[free, p])]
        if cost[best, p] + MARGIN_NATS <= cost[n, p]:
            out[best], out[n] = p, -1
    return out
