"""A bounded local refinement of the annealed particle filter's estimate (a step after the APF).

The APF (``apf``) ends with a cluster of particles around the maximum of w(X, Z); its weighted
mean is within the last layer's dispersion of it, not at it. This step finishes the
maximisation locally: from the APF estimate X_0 it solves

    min_X  1/2 sum_i rho(f_i(X)^2),   rho(z) = log(1 + z),   lower <= X <= upper,

over a measurement's residuals f (``KeypointMeasurement.residuals``, scaled by its sigma) with
Cauchy's loss, the APF energy's robust loss taken per image axis, by scipy's trust-region
reflective least squares, whose iterates stay inside the joint limits. The Jacobian is forward
differences, all D + 1 configurations posed in one batched forward-kinematics call. Bone lengths are the model's by
construction (the search is over angles and the root's position only).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from scipy.optimize import least_squares

from formulations.pose.body import BodyModel
from formulations.pose.kinematics import Posed, forward_kinematics
from formulations.pose.rotation import Array

STEP = 1e-6  # forward-difference step (radians; model units for the root's position)
INSIDE = 1e-9  # how far inside a limit the start is moved: the solver needs a strictly feasible start


class Residuals(Protocol):
    """A measurement that gives residuals ``(N, R)`` for N posed particles."""

    def residuals(self, posed: Posed) -> Array: ...


def refine(model: BodyModel, measurement: Residuals, start: Array, iterations: int = 30) -> Array:
    """``(D,)`` the configuration the module doc's local solve reaches from ``start`` (within the limits)."""
    lower, upper = model.lower, model.upper
    x0 = np.clip(start, lower + INSIDE, upper - INSIDE)
    steps = STEP * np.eye(model.dof)

    def residuals(x: Array) -> Array:
        values: Array = measurement.residuals(forward_kinematics(model, x[None]))[0]
        return values

    def jacobian(x: Array) -> Array:
        values = measurement.residuals(forward_kinematics(model, np.vstack([x, x + steps])))
        slopes: Array = ((values[1:] - values[0]) / STEP).T
        return slopes

    if residuals(x0).size == 0:
        unchanged: Array = model.clip(start[None])[0]
        return unchanged
    solution = least_squares(residuals, x0, jac=jacobian, bounds=(lower, upper), loss="cauchy", method="trf",
                             max_nfev=iterations)
    refined: Array = model.clip(solution.x[None])[0]
    return refined
