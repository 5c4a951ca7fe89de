"""A newcomer hypothesis inside the window: the lost object's return and a birth in one LP.

``returns.tested_chains`` settles a chain a lost object took after a miss outside the
window, one chain against one object, and then bars the object from it. Here the chain is
instead offered to the window as one more object P, the newcomer, and the window is solved
again with the lost object A and P both free to take it: the window's own optimum decides,
jointly with every other object and conflict set, which explains the boxes.

P's candidates are the chain's boxes in the window's frames and nothing else. Their template
costs price the newcomer in the units of the window's template term g (``costs``: a negative
log-likelihood less that of a box seen where predicted, -log p_ref(z) = log det R(z) / 2 +
2 log 2 pi): over the chain's boxes z_1..z_k up to the window's last frame (z_1 may be the
template frame's),

    T = -log p(z | new) + b - sum_j -log p_ref(z_j),

the density of ``returns.newcomer_nll`` (first box uniform over the image and box sizes,
the rest filtered from it with the people's velocity) plus the prior odds b of a birth
against a return (``births.BirthRates.newcomer_cost``). T is shared equally by P's boxes in
the window, so that P pays for the part of the chain it takes and never gains by leaving
its first box to A. Both sides then pay the window's arcs alike: c_a on entering from an
occluded template, lambda_2 per height of step off the own velocity (P's the people's mean,
not one fitted to the chain it is judged on), and c_a + c_b for each frame without a box,
so a frame one of them spends unseen cancels, and the LP gives the chain to A when A's
template terms along it cost less than T, which is ``returns.newcomer_wins``'s test with
A's side priced by the window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.boxes import kalman
from formulations.boxes.objects import BoxObjects, fitted_velocity
from formulations.boxes.returns import LOG_2PI_4D, newcomer_nll, population_rates

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


@dataclass(frozen=True)
class Newcomers:
    """Newcomer hypotheses posed for one window.

    Attributes:
        objects: One object per chain, at the template frame, its source occluded.
        detection: ``(C,)`` detection index of each fixed candidate.
        row: ``(C,)`` row in ``objects`` of each.
        cost: ``(C,)`` its template cost (module doc).
        first: ``(P,)`` each chain's first detection (it may lie at the template frame).
    """

    objects: BoxObjects
    detection: Ints
    row: Ints
    cost: Array
    first: Ints


def reference_nll(z: Array) -> Array:
    """``(k,)`` -log p_ref: the density of a box seen where predicted, measurement noise only."""
    noise = (kalman.MEASUREMENT_SD * np.maximum(z[:, 2:], 1.0)) ** 2
    result: Array = np.log(noise).sum(axis=1) + LOG_2PI_4D  # log det R / 2 with R's four variances
    return result


def newcomers(chains: list[Ints], seen: BoxObjects, frame: Ints, boxes: Array, histograms: Array | None,
              first_ident: int, template_frame: int, n_frames: int, volume: float,
              newcomer_cost: float) -> Newcomers:
    """A newcomer per chain (each holding at least one box in frames t0+1..t0+M), numbered from ``first_ident``.

    Args:
        chains: Detection indices in frame order, the first in frames t0..t0+M.
        seen: The objects alive at the template frame; those seen there give the newcomers'
            velocity (``returns.population_rates``; a chain's own fitted one if fewer).
        frame, boxes, histograms: All detections (corners; histograms None without frames).
        first_ident, template_frame, n_frames: Numbering, t0 and M.
        volume: Where a newcomer's first box may be (``likelihood.clutter_volume``).
        newcomer_cost: b.
    """
    there = seen.last_seen >= template_frame
    rates = population_rates(seen.mean[there], seen.covariance[there])
    end = template_frame + n_frames
    means, covariances, detection, row, cost = [], [], [], [], []
    for p, chain in enumerate(chains):
        part = chain[frame[chain] <= end]
        z = kalman.measurement(boxes[part])
        size = np.r_[z[0, 2:], z[0, 2:]]
        velocity = rates[0] * size if rates is not None else kalman.measurement(fitted_velocity(frame[part], boxes[part]))
        mean, covariance = kalman.start(z[:1] - (frame[part[0]] - template_frame) * velocity, velocity[None])
        means.append(mean[0])
        covariances.append(covariance[0])
        total = newcomer_nll(frame[part], z, volume, rates) + newcomer_cost - float(reference_nll(z).sum())
        inside = part[frame[part] > template_frame]
        detection.append(inside)
        row.append(np.full(len(inside), p))
        cost.append(np.full(len(inside), max(total, 0.0) / max(len(inside), 1)))
    n = len(chains)
    hist = None if histograms is None else np.array([histograms[c].mean(axis=0) for c in chains]).reshape(n, -1)
    objects = BoxObjects(np.arange(first_ident, first_ident + n), np.array(means).reshape(n, 8),
                         np.array(covariances).reshape(n, 8, 8), np.full(n, template_frame - 1), hist)
    flat = [np.concatenate(a) if a else np.zeros(0) for a in (detection, row, cost)]
    return Newcomers(objects, flat[0].astype(int), flat[1].astype(int), flat[2],
                     np.array([c[0] for c in chains], dtype=int))


def split_held(chains: list[Ints], owner: Ints, ident: Ints) -> tuple[list[Ints], list[Ints]]:
    """The chains holding no box an object of ``ident`` took (``owner``: ident per detection), and those holding some."""
    held = [bool(np.isin(owner[c], ident).any()) for c in chains]
    return [c for c, h in zip(chains, held) if not h], [c for c, h in zip(chains, held) if h]
