"""A lost object's return against a newcomer: the chain's likelihood under each, filtered.

When an object unseen for a while takes a chain of boxes z_1..z_k (frames f_1 < ... < f_k,
z = (cx, cy, w, h)), the chain is either the object back or a new person. Each hypothesis
gives the chain a density, computed the way a Kalman filter scores its innovations, one box
at a time, each predicted from the boxes before it only (``kalman``):

    -log p(z | lost) = sum_j [ r_j^T S_j^-1 r_j + log det S_j ] / 2 + 2 log 2 pi,   from the object's state,
    -log p(z | new)  = log V + (the same sum over j >= 2),                          from z_1,

r_j the innovation and S_j its covariance. The newcomer's first box is uniform over V (the
image area times the range of box widths and heights, ``likelihood.clutter_volume``); its
state starts there with the velocity of the people around it: per box size, the mean of the
rates of the objects seen at the template frame, with their spread plus their own
uncertainty as variance (``population_rates``; a walking camera moves everyone alike), or
``kalman.start``'s prior with fewer than three of them. The prior odds are the learned rates
of births and returns (``births.BirthRates``), so the newcomer takes the chain when

    -log lambda_B - log p(z | new)  <  -log h - log p(z | lost),

that is when ``-log p(z | new) + b < -log p(z | lost)``, b = ``BirthRates.newcomer_cost``.

Scoring each box against the forecast from the boxes before it, rather than every box
against one forecast from the window's template frame (the window's template term), pays a
lost object's spread once, at its first box back, and gives the newcomer no velocity fitted
to the boxes it is scored on.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.boxes import kalman
from formulations.boxes.objects import BoxObjects

Array = NDArray[np.float64]
Ints = NDArray[np.int_]

LOG_2PI_4D = 2.0 * np.log(2.0 * np.pi)
MIN_POPULATION = 3  # objects seen at the template frame needed for a velocity spread


def filtered_nll(mean: Array, covariance: Array, state_frame: int, frames: Ints, z: Array) -> float:
    """``-log p(z_1..z_k)`` under the Kalman filter from ``mean`` ``(8,)``, ``covariance``
    ``(8, 8)`` at ``state_frame``: each row of ``z`` ``(k, 4)`` scored by its predictive
    density at its frame (``frames`` increasing, after ``state_frame``), then filtered in."""
    x, p = mean[None].copy(), covariance[None].copy()
    at, total = state_frame, 0.0
    for f, zj in zip(frames, z):
        for _ in range(int(f) - at):
            x, p = kalman.predict(x, p)
        at = int(f)
        predicted, s = kalman.innovation(x, p)
        r = zj - predicted[0]
        total += 0.5 * (float(r @ np.linalg.solve(s[0], r)) + float(np.linalg.slogdet(s[0])[1])) + LOG_2PI_4D
        x, p = kalman.update(x, p, zj[None])
    return total


def population_rates(mean: Array, covariance: Array) -> Array | None:
    """``(2, 4)`` mean and variance of the rates per size (w, h, w, h) of objects with states
    ``mean`` ``(N, 8)``, ``covariance`` ``(N, 8, 8)``; None for fewer than ``MIN_POPULATION``."""
    if len(mean) < MIN_POPULATION:
        return None
    size = np.maximum(np.concatenate([mean[:, 2:4], mean[:, 2:4]], axis=1), 1.0)
    rate = mean[:, 4:] / size
    own = np.einsum("nii->ni", covariance[:, 4:, 4:]) / size**2
    return np.stack([rate.mean(axis=0), rate.var(axis=0, ddof=1) + own.mean(axis=0)])


def newcomer_nll(frames: Ints, z: Array, volume: float, rates: Array | None = None) -> float:
    """``-log p(z_1..z_k)`` of a new object: z_1 uniform over ``volume`` (pixel^4), the rest
    filtered from a start at z_1 with velocity prior ``rates`` (``population_rates``) or, if None, ``kalman.start``'s."""
    mean, covariance = kalman.start(z[:1])
    if rates is not None:
        size = np.r_[z[0, 2:], z[0, 2:]]
        mean[0, 4:] = rates[0] * size
        covariance[0, 4:, 4:] = np.diag(rates[1] * size**2)
    return float(np.log(volume)) + filtered_nll(mean[0], covariance[0], int(frames[0]), frames[1:], z[1:])


def newcomer_wins(mean: Array, covariance: Array, state_frame: int, frames: Ints, boxes: Array, volume: float,
                  newcomer_cost: float, rates: Array | None = None) -> bool:
    """True when the chain of corner ``boxes`` ``(k, 4)`` at ``frames`` is better explained by
    a new object than by the lost one whose state at ``state_frame`` is ``mean``, ``covariance``
    (module doc; ``newcomer_cost`` is b, ``rates`` the newcomer's velocity prior)."""
    z = kalman.measurement(boxes)
    newcomer = newcomer_nll(frames, z, volume, rates) + newcomer_cost
    return newcomer < filtered_nll(mean, covariance, state_frame, frames, z)


def tested_chains(chains: list[Ints], objects: BoxObjects, owner: Ints, frame: Ints, boxes: Array, template_frame: int,
                  volume: float, newcomer_cost: float) -> tuple[list[Ints], list[tuple[int, Ints]]]:
    """The chains that are new objects, and for each one a newcomer won, (row of the object, the chain).

    A chain holding no box an object in ``objects`` took (``owner``: ident per detection) is
    a birth as before; one holding some is tested against the first such object
    (``newcomer_wins``, newcomer velocity from the objects seen at ``template_frame``) and kept
    only if the newcomer wins.
    """
    seen = objects.last_seen >= template_frame
    rates = population_rates(objects.mean[seen], objects.covariance[seen])
    kept: list[Ints] = []
    barred: list[tuple[int, Ints]] = []
    for chain in chains:
        held = owner[chain][np.isin(owner[chain], objects.ident)]
        if not len(held):
            kept.append(chain)
            continue
        row = int(np.flatnonzero(objects.ident == held[0])[0])
        if newcomer_wins(objects.mean[row], objects.covariance[row], template_frame, frame[chain], boxes[chain], volume,
                         newcomer_cost, rates):
            kept.append(chain)
            barred.append((row, chain))
    return kept, barred
