"""Best view by dynamic programming over a sliding window (Jiang, Fels & Little 2008, Sec. III).

For one object, M cameras and a cost c(n, b) of showing it from camera b at frame n
(lower is better), each sliding window spans the previous decision b_{-1}, the current
frame 0 and the next N - 1 frames, and solves

    min_{b_0 .. b_{N-1}}  sum_{n=0}^{N-1} c(n, b_n) + lambda sum_{n=0}^{N-1} d(b_n, b_{n-1}),

    d(x, y) = 0 if x = y, 1 otherwise                                       (1)

(the paper writes d = delta(x - y) and says what it means: no cost for keeping the
camera, a constant one for a switch). Only b_0* is kept; the window slides one frame,
b_0* becomes the next b_{-1}. The very first b_{-1} is the view with the best
measurement at frame 0 (step 1 of the paper's algorithm). Near the end of the take a
window holds the frames that remain.

The paper solves each window by a forward Viterbi pass from b_{-1} and a backtrack to
f_0. This module evaluates the same window optimum backwards, with the cost-to-go

    V_{N-1}(m) = c(N-1, m),
    V_n(m)     = c(n, m) + min(V_{n+1}(m), min_i V_{n+1}(i) + lambda),       (2)

so that b_0* = argmin_m lambda d(m, b_{-1}) + V_0(m). V_0 does not depend on b_{-1}:
it is computed for every start frame and every object at once (N vectorised steps of
(2)), and the slide itself is one argmin per frame. Both passes minimise (1) over the
same window; where several sequences tie, this one keeps b_{-1} if it is among the
optimal first choices, else the lowest camera index.

A camera may be ruled out of a frame (``allowed`` False: it took no marker there, so
naming it would point at a picture without the object). No finite cost can say so: the
cost of a camera that does not show the object is 1, and it ties with a switch at
lambda = 1, where the tie keeps b_{-1}. A ruled-out camera costs +inf in (2): V is
then +inf exactly where the camera is ruled out (each frame keeps an allowed camera,
so min_i V is finite and no inf - inf arises), the DP stays the exact minimum of (1)
over the allowed sequences, and a ruled-out b_{-1} is never kept.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from formulations.errors import FormulationError

# |cost| bound: a window sums at most (frames) costs and switch prices, so with this bound
# and any take that fits in memory the sums stay finite; no view-quality scale comes near it.
MAX_COST = 1e100


def select_views(
    costs: npt.ArrayLike, switch_cost: float, window: int, allowed: npt.ArrayLike | None = None,
) -> npt.NDArray[np.int64]:
    """Each object's camera in each frame, by Jiang's sliding-window DP.

    Args:
        costs: ``(F, K, M)`` cost c(n, b) of camera b for object k at frame n, finite,
            lower is better.
        switch_cost: lambda >= 0, the price of one camera switch in the units of ``costs``.
        window: N >= 1 frames per window, the current frame included (N = 1 with any
            lambda is the greedy filter that switches when one frame pays for it).
        allowed: ``(F, K, M)`` False where camera b may not be chosen (module doc); every
            frame and object needs one allowed camera. None: every camera is allowed.

    Returns:
        ``(F, K)`` chosen camera index b_n* per frame and object.

    Raises:
        FormulationError: a cost array that is not (F, K, M) with M >= 1, a non-finite
            cost or one past ``MAX_COST``, a negative or non-finite lambda, a window under one frame,
            or an ``allowed`` mask of another shape or with a frame and object that allows no camera.
    """
    c = _ruled_out(_checked(costs, switch_cost, window), allowed)
    n_frames, n_objects, _ = c.shape
    # Past the end a window is zero-cost padding, which changes no choice (see _cost_to_go):
    # a window longer than the take gives exactly the result of one as long as the take.
    window = min(window, max(n_frames, 1))
    to_go = _cost_to_go(c, switch_cost, window)
    # Keeping b_{-1} is optimal iff V_0(b_{-1}) <= min_m V_0(m) + lambda; otherwise the
    # overall argmin of V_0 is another camera, and the best one to switch to.
    best, switch_bound = np.argmin(to_go, axis=2), to_go.min(axis=2) + switch_cost
    chosen = np.empty((n_frames, n_objects), dtype=np.int64)
    objects = np.arange(n_objects)
    previous = np.argmin(c[0], axis=1) if n_frames else np.empty(0, dtype=np.int64)
    for n in range(n_frames):
        previous = np.where(to_go[n, objects, previous] <= switch_bound[n], previous, best[n])
        chosen[n] = previous
    return chosen


def _cost_to_go(c: npt.NDArray[np.float64], switch_cost: float, window: int) -> npt.NDArray[np.float64]:
    """``(F, K, M)`` V_0 of (2) for the window starting at every frame.

    Frames past the end are padded with zero cost: a constant V needs no switch, so a
    padded window has the optimum of the frames that remain.
    """
    n_frames = c.shape[0]
    padded = np.concatenate([c, np.zeros((window - 1,) + c.shape[1:])])
    to_go = np.zeros_like(c)
    for n in range(window - 1, -1, -1):
        carried = np.minimum(to_go, to_go.min(axis=2, keepdims=True) + switch_cost)
        to_go = padded[n : n + n_frames] + carried
    return to_go


def _ruled_out(c: npt.NDArray[np.float64], allowed: npt.ArrayLike | None) -> npt.NDArray[np.float64]:
    """``c`` with +inf where ``allowed`` is False (module doc)."""
    if allowed is None:
        return c
    mask = np.asarray(allowed)
    if mask.shape != c.shape:
        raise FormulationError(f"best view: allowed must have the costs' shape {c.shape}, got {mask.shape}")
    mask = mask.astype(bool)
    if not mask.any(axis=2).all():
        raise FormulationError("best view: every frame and object needs an allowed camera")
    return np.where(mask, c, np.inf)


def _checked(costs: npt.ArrayLike, switch_cost: float, window: int) -> npt.NDArray[np.float64]:
    try:
        c = np.asarray(costs, dtype=float)
    except (TypeError, ValueError):
        raise FormulationError("best view: costs must be numeric") from None
    if c.ndim != 3 or c.shape[2] < 1:
        raise FormulationError(f"best view: costs must be (frames, objects, cameras) with a camera, got shape {c.shape}")
    if not (np.isfinite(c).all() and (np.abs(c) <= MAX_COST).all()):
        raise FormulationError(f"best view: costs must be finite, within +-{MAX_COST:g}")
    if not (np.isfinite(switch_cost) and switch_cost >= 0):
        raise FormulationError(f"best view: switch cost must be finite and >= 0, got {switch_cost}")
    if window < 1:
        raise FormulationError(f"best view: window must be at least 1 frame, got {window}")
    return c
