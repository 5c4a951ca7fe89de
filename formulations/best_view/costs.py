"""View costs from view qualities: the share of the frame's best view that a camera loses.

A quality q(n, b) >= 0 says how well camera b shows an object at frame n (0: not at
all). The DP (``selection``) wants a cost, lower is better, on one scale across frames:

    c(n, b) = 1 - q(n, b) / max_i q(n, i),       c(n, b) = 1 for all b when max_i q(n, i) = 0.

The best camera of a frame costs 0, a camera that does not show the object costs 1,
whatever the object's size or distance. The switch cost lambda is then counted in
frames of the best view: lambda = 2 trades a switch against two frames shown from a
camera with nothing of the object, or four at half the best quality.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from formulations.errors import FormulationError


def relative_costs(quality: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``(..., M)`` costs 1 - q / max q over the last axis (cameras).

    Raises:
        FormulationError: a negative or non-finite quality.
    """
    q = np.asarray(quality, dtype=float)
    if not (np.isfinite(q).all() and (q >= 0).all()):
        raise FormulationError("best view: view qualities must be finite and >= 0")
    best = q.max(axis=-1, keepdims=True) if q.shape[-1] else np.zeros(q.shape[:-1] + (1,))
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(best > 0, q / best, 0.0)
    costs: npt.NDArray[np.float64] = 1.0 - share
    return costs
