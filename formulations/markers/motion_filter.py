"""A constant-velocity Kalman filter per marker: where a marker seen in a row will be next.

The raw constant-velocity prediction x_t + (x_t - x_(t-1)) extrapolates two noisy points, so
its error has per-axis variance 5 sigma^2 from noise alone (6 sigma^2 with the point it is
compared to): at 4 mm of noise about 10 mm per axis, as much as half the spacing of a wrist's
or a clavicle's markers. Filtering each marker's track (per axis, state position and
velocity, Bar-Shalom's discrete white-noise acceleration model) averages the noise over the
frames its motion allows:

    predict:  x- = x + v,   P- = F P F' + q^2 [[1/4, 1/2], [1/2, 1]],   F = [[1, 1], [0, 1]]
    update:   S = P-_xx + sigma^2,   K = P-_x. / S,   (x, v) = (x-, v-) + K (z - x-),
              P = (I - K H) P-

with sigma^2 the take's measurement noise and q^2 the marker's own acceleration per frame,
both learned as the take is labeled: q^2 = s^2 - 6 sigma^2 from the running mean s^2 of the
marker's squared constant-velocity residual (6 sigma^2 + q^2, ``motion``), and sigma^2 from the lag-one products of
consecutive residuals, which noise alone makes -4 sigma^2 (e_t = n_t - 2 n_(t-1) + n_(t-2);
an acceleration that persists makes them positive, so sigma^2 comes out low and the filter
nearer the raw prediction: the safe side). With sigma^2 = 0 the filter is the raw prediction.
A white acceleration is a poor model of a limb's: it lags behind a smooth swing the raw
prediction follows. Its gain is averaging noise, so a marker predicts by the filter only where
the noise is at least half its raw residual (6 sigma^2 >= q^2, i.e. s^2 <= 12 sigma^2) and the
filter has erred less than the raw prediction on its own frames so far (running means of the
squared errors, ``motion.learn_motion``): on a noisy take, or a still marker. Everywhere it
erred less, the filter cost the seed-0 accuracy matrix 0.15-0.23 points at 1.5 and 2 mm (up to
5 on the tennis serve and racing) for 0.78 at 4 mm; with the noise condition, over seeds 0-2,
+0.93 at 4 mm, +0.09 at 2 mm, -0.08 at 1.5 mm (docs/how-a-window-is-solved.md). A limb that
suddenly accelerates (a serve) leaves a filter tuned to its calm behind: a point off the
forecast by more than the 99.9 % chi-square of S starts the filter again from the last two points.

The filter holds only while a marker is seen frame after frame on the points it filtered
(``raw``: the last point it took, NaN when none): anything else that moves a marker (a
reappearance, an exchange repair, a model placing it) falls back on the raw prediction, and
two sightings in a row start the filter again.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from formulations.markers.motion import MOTION_VAR_PRIOR_MM2, learn_motion

NOISE_RATE = 0.02  # one frame's pooled lag products, once about 50 have been learned
MANOEUVRE_CHI2 = 16.27  # chi-square, 3 degrees of freedom, 99.9 %
# Below this the filter's gain, at most the raw forecast's noise error sqrt(5) sigma per axis
# (1.1 mm), is a tenth of the closest markers' spacing: it cannot part markers, only tip near-ties.
MIN_NOISE_SD_MM = 0.5


class FilteredMarkers(Protocol):
    """What the filter reads of a ``MarkerState`` (a protocol: the state imports this module)."""

    @property
    def position(self) -> np.ndarray: ...
    @property
    def visible(self) -> np.ndarray: ...
    @property
    def last_residual(self) -> np.ndarray: ...
    @property
    def burst_var(self) -> np.ndarray: ...
    @property
    def motion_samples(self) -> np.ndarray: ...
    @property
    def filtered(self) -> np.ndarray: ...
    @property
    def filter_cov(self) -> np.ndarray: ...
    @property
    def filter_raw(self) -> np.ndarray: ...
    @property
    def residual_var(self) -> np.ndarray: ...
    @property
    def filter_var(self) -> np.ndarray: ...
    @property
    def noise_var(self) -> np.ndarray: ...
    @property
    def noise_samples(self) -> np.ndarray: ...


def initial_filter(n: int) -> dict[str, np.ndarray]:
    """The filter fields of ``n`` markers' first ``MarkerState``: nothing filtered, no noise known."""
    return dict(
        filtered=np.zeros((n, 2, 3)), filter_cov=np.zeros((n, 3)), filter_raw=np.full((n, 3), np.nan),
        residual_var=np.full(n, MOTION_VAR_PRIOR_MM2), filter_var=np.full(n, MOTION_VAR_PRIOR_MM2),
        noise_var=np.zeros(n), noise_samples=np.zeros(n, int),
    )


def filter_holds(raw: np.ndarray, position: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """``(N,)`` bool where the filter holds: seen on the point it filtered last (module doc)."""
    holds: np.ndarray = visible & np.logical_and.reduce(raw == position, axis=1)  # .all's wrappers cost more
    return holds


def filter_predicts(state: FilteredMarkers) -> np.ndarray:
    """``(N,)`` bool where the filter holds, noise is at least half the raw residual and at
    least ``MIN_NOISE_SD_MM``, and the filter has erred less than the raw prediction (module doc)."""
    noisy = (state.residual_var <= 12 * state.noise_var) & (state.noise_var >= MIN_NOISE_SD_MM**2)
    predicts: np.ndarray = filter_holds(state.filter_raw, state.position, state.visible) & noisy
    return predicts & (state.filter_var < state.residual_var)


def advance_filter(
    state: FilteredMarkers, observed: np.ndarray, seen: np.ndarray, residual: np.ndarray, usable: np.ndarray,
) -> dict[str, np.ndarray]:
    """The filter fields of ``state`` one frame later (``MarkerState.advance``).

    Args:
        observed, seen: this frame's points and which markers took one.
        residual: ``(N, 3)`` the points off the raw constant-velocity prediction.
        usable: ``(N,)`` seen now and in the two frames before.
    """
    holds = filter_holds(state.filter_raw, state.position, state.visible)
    lagged = usable & np.logical_or.reduce(state.last_residual != 0, axis=1)
    noise_var, noise_samples = learn_noise(float(state.noise_var[0]), int(state.noise_samples[0]), residual,
                                           state.last_residual, lagged)
    filtered, cov, raw, innovation = filter_step(
        state.filtered, state.filter_cov, holds, observed, seen, state.visible & seen, state.position,
        max(float(state.noise_var[0]), 0.0), state.residual_var, state.burst_var,  # persisting motion can make it < 0
    )
    residual_var, _ = learn_motion(state.residual_var, state.motion_samples, residual, usable, decay=1.0)
    filter_var, _ = learn_motion(state.filter_var, state.motion_samples, innovation, usable & holds, decay=1.0)
    return dict(
        filtered=filtered, filter_cov=cov, filter_raw=raw, residual_var=residual_var, filter_var=filter_var,
        noise_var=np.full_like(state.noise_var, noise_var), noise_samples=np.full_like(state.noise_samples, noise_samples),
    )


def filter_step(
    filtered: np.ndarray, cov: np.ndarray, holds: np.ndarray, observed: np.ndarray, seen: np.ndarray,
    was_seen: np.ndarray, previous: np.ndarray, noise_var: float, residual_var: np.ndarray,
    burst_var: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Filtered state ``(N, 2, 3)``, covariance ``(N, 3)`` (xx, xv, vv) and raw point ``(N, 3)``
    one frame later (module doc), and the innovation ``(N, 3)``: the point off the forecast.

    Args:
        holds: ``(N,)`` the filter held at the frame before (``filter_holds``).
        observed, seen: this frame's points and which markers took one.
        was_seen, previous: seen in the frame before too, and where.
        noise_var: sigma^2, per axis (mm^2).
        residual_var: ``(N,)`` s^2, the markers' constant-velocity residual variance per axis.
    """
    # Run once per marker state advanced, on a few dozen markers: numpy's per-call overhead is
    # the cost, so few calls, the two rows of the state at once, and no stack or tile.
    r = noise_var
    q2 = np.maximum(residual_var - 6 * r, burst_var)
    c_xx, c_xv, c_vv = cov.T
    prior = np.empty((len(cov), 2))  # P-_xx, P-_xv: the gain's numerators, side by side
    np.add(c_xx + 2 * c_xv + c_vv, q2 / 4, out=prior[:, 0])
    np.add(c_xv + c_vv, q2 / 2, out=prior[:, 1])
    s = np.maximum(prior[:, 0] + r, 1e-12)
    gain = prior / s[:, None]
    forecast = filtered.copy()  # F (x, v): (x + v, v)
    forecast[:, 0] += filtered[:, 1]
    innovation = observed - forecast[:, 0]
    # A point this far off the filter's forecast is a manoeuvre it lags behind: start again.
    surprised = np.add.reduce(innovation * innovation, axis=1) / s > MANOEUVRE_CHI2
    keep = seen & holds & ~surprised
    start = seen & was_seen & ~holds
    forecast += gain[:, :, None] * innovation[:, None]
    new_filtered = np.where(keep[:, None, None], forecast, filtered)
    updated_cov = np.empty_like(cov)
    np.multiply((1 - gain[:, :1]), prior, out=updated_cov[:, :2])
    np.subtract(c_vv + q2, gain[:, 1] * prior[:, 1], out=updated_cov[:, 2])
    new_cov = np.where(keep[:, None], updated_cov, cov)
    if start.any():  # rare: after a gap or a repair
        # Two sightings in a row start it: velocity their difference (variance 2 sigma^2).
        new_filtered[start, 0], new_filtered[start, 1] = observed[start], observed[start] - previous[start]
        new_cov[start] = (r, r, 2 * r)
    raw = np.where((keep | start)[:, None], observed, np.nan)
    return new_filtered, new_cov, raw, innovation


def learn_noise(
    var: float, samples: int, residual: np.ndarray, last_residual: np.ndarray, usable: np.ndarray,
) -> tuple[float, int]:
    """The running mean over frames of -e_t . e_(t-1) / (3 * 4), averaged over the markers with a
    residual this frame and the last, and the frames it has learned from. It can come out
    negative where an acceleration persists; the filter takes sigma^2 as it floored at 0."""
    rows = np.flatnonzero(usable)
    if not len(rows):
        return var, samples
    # add.reduce / count is what .sum(axis=1).mean() computes, without its wrappers' overhead
    lag = -float(np.add.reduce(np.add.reduce(residual[rows] * last_residual[rows], axis=1)) / len(rows)) / 12.0
    rate = max(1.0 / (samples + 2), NOISE_RATE)
    return var + rate * (lag - var), samples + 1
