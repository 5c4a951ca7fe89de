"""Random box-tracking windows in the manner of Jiang et al. (2008), Sec. IV-A5 / Table I.

Objects move as boxes in a CIF image (352 x 288) with a 64-bin grey histogram each;
every frame holds ``n_observations`` boxes: one noisy detection of each object (unless
dropped) plus clutter with random histograms. Every observation is a candidate of
every object, so all objects share every observation (one conflict group each).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights

IMAGE = np.array([352.0, 288.0])
BINS = 64


@dataclass(frozen=True)
class JiangInstance:
    """A generated window: candidates, cost weights, and the true observation per object/frame."""

    candidates: WindowCandidates
    weights: ArcCostWeights
    truth: np.ndarray  # (N, M) index of the true observation within its frame, -1 if dropped


def jiang_instance(
    n_objects: int = 3, n_frames: int = 20, n_observations: int = 50, seed: int = 0,
    drop_rate: float = 0.05, histogram_noise: float = 0.3,
) -> JiangInstance:
    """One window of Jiang's random instance; frames 1..n_frames after a template."""
    rng = np.random.default_rng(seed)
    base = rng.dirichlet(np.full(BINS, 0.5), size=n_objects)
    corners = _object_boxes(rng, n_objects, n_frames + 1)  # (N, M+1, 4)
    boxes = _random_boxes(rng, (n_frames, n_observations))
    hists = rng.dirichlet(np.full(BINS, 0.5), size=(n_frames, n_observations))
    truth = np.full((n_objects, n_frames), -1)
    for m in range(n_frames):
        slots = rng.permutation(n_observations)[:n_objects]
        seen = rng.random(n_objects) >= drop_rate
        truth[seen, m] = slots[seen]
        boxes[m, slots[seen]] = corners[seen, m + 1] + rng.normal(0, 2.0, size=(seen.sum(), 4))
        noisy = base[seen] + histogram_noise * rng.dirichlet(np.full(BINS, 0.5), size=seen.sum())
        hists[m, slots[seen]] = noisy / noisy.sum(axis=1, keepdims=True)
    obs = n_frames * n_observations
    flat_boxes, flat_hists = boxes.reshape(obs, 4), hists.reshape(obs, BINS)
    objects = np.repeat(np.arange(n_objects), obs)
    ids = np.tile(np.arange(obs), n_objects)
    template_cost = 0.5 * np.abs(flat_hists[None] - base[:, None]).sum(axis=2).ravel()
    candidates = WindowCandidates(
        template_location=corners[:, 0], template_occluded=np.zeros(n_objects, bool), n_frames=n_frames,
        object=objects, frame=ids // n_observations + 1, location=flat_boxes[ids],
        template_cost=4.0 * template_cost,
        resources=sp.csr_matrix((np.ones(len(ids)), (np.arange(len(ids)), ids)), shape=(len(ids), obs)),
        occlusion_location=corners[:, 1:], motion=np.diff(corners, axis=1),
        appearance=flat_hists[ids], template_appearance=base,
    )
    weights = ArcCostWeights(appearance_change=2.0, displacement=0.05, reappear=1.5, disappear=1.5)
    return JiangInstance(candidates=candidates, weights=weights, truth=truth)


def _object_boxes(rng: np.random.Generator, n: int, frames: int) -> np.ndarray:
    """Boxes moving with constant velocity, crossing one another in the image."""
    start = rng.uniform(0.2, 0.8, size=(n, 2)) * IMAGE
    velocity = rng.normal(0, 3.0, size=(n, 2))
    centre = start[:, None] + velocity[:, None] * np.arange(frames)[None, :, None]
    size = rng.uniform([20, 50], [40, 90], size=(n, 2))[:, None]
    return np.concatenate([centre - size / 2, centre + size / 2], axis=2)


def _random_boxes(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    centre = rng.uniform(0, 1, size=shape + (2,)) * IMAGE
    size = rng.uniform([20, 50], [40, 90], size=shape + (2,))
    return np.concatenate([centre - size / 2, centre + size / 2], axis=-1)
