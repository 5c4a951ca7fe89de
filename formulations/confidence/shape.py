"""Whose point is it? The probability, from the learned shape alone, that each seen marker's
point is its own.

A window's margin (``margins``) judges its reading against the readings the window's costs
allow; a marker re-acquired on a lost neighbour's point, or two neighbours exchanged for
good, can be the cheapest reading by several nats and still be wrong. What such a label
breaks is the shape: the marker's distances to its neighbours (learned up to the window,
``MarkerState.distance_mean`` / ``distance_var``) fit another marker's point better.

With D[j, x] the shape deviation of marker j placed at x (``exchange.shape_deviations``,
a weighted mean of | ||x - r_k|| - dbar_jk | over j's seen neighbours k, in mm), read it as
half-normal with the matching weighted mean of the learned distance s.d.s,

    f_j(x) = sqrt(2 / pi) / s_j exp(-D[j, x]^2 / (2 s_j^2)),   s_j = sum_k a_jk sd_jk / sum_k a_jk,

(s_j at least 1 mm). Marker m holds x_m at the window's last frame. Its identity
hypotheses, equally likely before the shape is seen, are: m itself; any marker m' not seen
there (m took the point of a lost marker); any seen marker m' (the two
exchanged, likelihood f_m'(x_m) f_m(x_m') / f_m'(x_m') relative to m' keeping its own). So

    p(m) = f_m(x_m) / (f_m(x_m) + sum_{m' lost} f_m'(x_m) + sum_{m' seen} f_m'(x_m) f_m(x_m') / f_m'(x_m')),

in logarithms (a log-sum-exp), 1 where m has no seen neighbour (nothing to judge by).
Only the judged markers (the service's: those re-acquired in a window) are priced, and the
exchange partners m' are the judged markers and their seen neighbours: a marker far from m
gives f_m'(x_m) ~ 0, and pricing every pair costs N^2 K distances per window.
A ghost is no hypothesis here: its density (uniform over the gate) is not comparable
with a marker's when the learned s.d.s are loose, and it flagged right labels.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.markers.exchange import shape_deviations
from formulations.markers.state import MarkerState

MIN_SD_MM = 1.0  # s_j floor: a learned s.d. below the noise is no tighter evidence


def shape_log_density(
    template: MarkerState, end: MarkerState, rows: NDArray[np.intp], at: NDArray[np.intp],
) -> NDArray[np.float64]:
    """``(R, P)`` log f_j(x_p): marker ``rows[r]`` at the position of marker ``at[p]`` at ``end``.

    Args:
        template: The state the window was posed from: the shape learned before it.
        end: The state at the window's last frame: the positions and which markers are seen.
        rows, at: The markers judged, and the markers whose positions they are judged at.
    """
    # The rows' own neighbour lists and statistics; positions and visibility stay whole,
    # as the neighbour indices point into them.
    learned = replace(
        end, neighbours=end.neighbours[rows], distance_mean=template.distance_mean[rows],
        distance_var=template.distance_var[rows],
    )
    deviation = shape_deviations(learned, end.position[at])
    weight = end.visible[learned.neighbours] / (learned.distance_var + 1.0)
    sd = (weight * np.sqrt(learned.distance_var)).sum(axis=1) / np.maximum(weight.sum(axis=1), 1e-12)
    sd = np.maximum(sd, MIN_SD_MM)[:, None]
    finite = np.isfinite(deviation)
    log_f = 0.5 * np.log(2 / np.pi) - np.log(sd) - 0.5 * (np.where(finite, deviation, 0.0) / sd) ** 2
    result: NDArray[np.float64] = np.where(finite, log_f, -np.inf)
    return result


def shape_identity(template: MarkerState, end: MarkerState, judged: NDArray[np.intp]) -> NDArray[np.float64]:
    """p(m) of the module doc for the seen markers ``judged`` (``(R,)``); 1 for a marker
    with no seen neighbour. Exchange partners: the judged markers and their seen neighbours."""
    partners = np.union1d(judged, end.neighbours[judged][end.visible[end.neighbours[judged]]])
    lost = np.flatnonzero(~end.visible)
    log_f = shape_log_density(template, end, np.concatenate([partners, lost]), partners)  # (S + L, S)
    within = np.searchsorted(partners, judged)  # judged m as a partner
    own_all = np.diag(log_f[: len(partners)])  # log f_m'(x_m') of every partner
    own = own_all[within]
    at_judged = log_f[:, within]  # [j, r]: log f_j(x_r)
    with np.errstate(invalid="ignore"):  # -inf - -inf where a partner has no shape: masked by usable
        exchanged = at_judged[: len(partners)] + log_f[within].T - own_all[:, None]  # [m', r]
    usable = (partners[:, None] != judged[None, :]) & np.isfinite(own_all)[:, None]
    hypotheses = np.concatenate([np.where(usable, exchanged, -np.inf), at_judged[len(partners):]], axis=0)
    top = hypotheses.max(axis=0, initial=-np.inf)
    shift = np.where(np.isfinite(top), top, 0.0)
    with np.errstate(divide="ignore"):  # no hypothesis: log 0 = -inf, p = 1
        alternatives = shift + np.log(np.exp(hypotheses - shift).sum(axis=0))
    probability = 1.0 / (1.0 + np.exp(np.minimum(alternatives - np.where(np.isfinite(own), own, 0.0), 700.0)))
    return np.where(np.isfinite(own), probability, 1.0)
