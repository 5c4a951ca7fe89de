"""Candidates for unlabeled 3D point clouds: the points inside each marker's gate.

For marker n and frame m the candidates are the points within the gate radius of the
predicted position p_n(m) (constant velocity from the template and the frames before,
along the guide track). A candidate consumes its point id, so two markers gating the
same point conflict. The template term (Jiang's g(s_n, v), here a marker's "appearance")
has two parts:

    g(s_n, v) = w_p min(||r_v - p_n(m)|| / sigma(k), cap)
              + w_s sum_j a_j min(| ||r_v - p_j(m)|| - dbar_nj |, c) / max(sum_j a_j, a_0)

The first prefers candidates near the prediction, measured in units of its uncertainty
sigma(k) = sigma_0 + k sigma_1 after k unseen frames (measured on CMU 85_02 and 135_02:
the 90th percentile of the prediction error grows by about 2.5 mm a frame): a marker with
a sure prediction must not take a point far from it, while one lost for long may. It is
capped so a bad prediction cannot veto the true track. The
second is the shape signature: the distances from the candidate to the predicted
positions of the marker's neighbours j against their learned means dbar_nj, weighted by
a_j = 1 / (var_nj + 1) over neighbours tracked in the previous frame (Ringer & Lasenby
2004: markers on one segment keep their distances). It is what stops a marker from
inheriting the track of an occluded neighbour. For a marker a firm rigid fit carries, a_j
counts its carriers only (``MarkerState.carriers``): distances are learned from sightings,
so a wrist learned rigid with a still thigh stays so while it is carried up and away, and
only the carry knows better.

A track of points no marker holds that is seeded at the template (``markers.unnamed``) was
seen beside every marker seen there, and beside an unseen marker whose last point the track
passed elsewhere (``coexistence``): no such marker is a candidate for its points
(``_beside_seeds``). Priced alone, a lost marker pays one dear step onto such a track and
then saves a miss every frame, while the track's own miss is free.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import chain

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from formulations.markers.guide import Gate, GuideTrack, guide_track
from formulations.markers.lengths import lengths
from formulations.markers.likelihood import marker_likelihood
from formulations.markers.state import MarkerState
from formulations.markers.step_motion import HALF_WIDTH, expected_steps
from formulations.markers.unnamed import UnnamedChains, WindowSurround, unnamed_chains
from formulations.window.candidates import WindowCandidates

SHAPE_CAP_MM = 50.0  # c
SHAPE_WEIGHT_FLOOR = 0.05  # a_0: the weight of one neighbour whose distance varies by ~4 mm


@dataclass(frozen=True)
class CloudGating:
    """How cloud candidates are gated and priced.

    Attributes:
        gate: Gate radius around the prediction.
        prediction_weight: w_p, cost per sigma between a candidate and the prediction.
        prediction_sigma_mm: sigma_0, uncertainty of a prediction for a marker seen last frame.
        prediction_sigma_growth_mm: sigma_1, added per frame unseen.
        prediction_cap_sigmas: cap, in sigmas, beyond which the prediction term stops growing.
        shape_weight: w_s, cost per mm of mean deviation from the learned neighbour distances.
        likelihood: Price steps, reappearances and occlusions as negative log-likelihoods
            learned from the take (``markers.likelihood``); the prediction term above and
            the arc weights' constants are then not used.
        step_median_frames: h of the expected step, the median of the guide's steps
            h frames each side (``markers.step_motion``); 0: the guide's last step, which
            looks at no later frame (the frame-by-frame baseline).
        unnamed_tracks: Points no marker holds that persist are objects of the window
            (``markers.unnamed``; with ``likelihood`` only), not clutter each frame.
    """

    gate: Gate = field(default_factory=Gate)
    prediction_weight: float = 2.0
    prediction_sigma_mm: float = 4.0
    prediction_sigma_growth_mm: float = 2.5
    prediction_cap_sigmas: float = 6.0
    shape_weight: float = 0.5
    likelihood: bool = True
    step_median_frames: int = HALF_WIDTH
    unnamed_tracks: bool = True


@dataclass(frozen=True)
class CloudWindow:
    """Candidates of one window and what maps them back to the input points."""

    candidates: WindowCandidates
    frame: np.ndarray  # (C,) window frame 1..M of each candidate
    point: np.ndarray  # (C,) index of the point within its frame
    guide: GuideTrack


def cloud_candidates(
    state: MarkerState, frames: list[np.ndarray], gating: CloudGating = CloudGating(),
    point_resources: list[sp.csr_matrix] | None = None, around: WindowSurround | None = None,
) -> CloudWindow:
    """Gate every frame's points around the guide track's predictions.

    Args:
        state: The markers at the template frame.
        frames: ``(points, 3)`` per window frame.
        gating: Gates and template-term weights.
        point_resources: Per frame, ``(points, R_f)`` 0/1: what each point consumes when
            points are not independent (triangulated points sharing a camera detection).
            None: each point is its own resource.
        around: The points next to the window: with them (and ``gating.likelihood``) its
            unnamed tracks (``markers.unnamed``) are objects N.., each with its own chain's
            points as candidates.
    """
    guide = guide_track(state, frames, gating.gate)
    unnamed = UnnamedChains.empty(len(frames))
    if around is not None and gating.likelihood and gating.unnamed_tracks:
        unnamed = unnamed_chains(state, around, frames, gating.gate, guide)
    objects, frame_of, points = [], [], []
    for f, cloud in enumerate(frames):
        if len(cloud) == 0:
            continue
        inside = cKDTree(cloud).query_ball_point(guide.predicted[f], guide.radius[f])
        counts = np.fromiter(map(len, inside), dtype=int, count=len(inside))
        objects.append(np.repeat(np.arange(len(inside)), counts))
        points.append(np.fromiter(chain.from_iterable(inside), dtype=int, count=counts.sum()))  # C-level, not a generator
        frame_of.append(np.full(counts.sum(), f + 1))
    obj, frame, point = (np.concatenate(a) if a else np.zeros(0, int) for a in (objects, frame_of, points))
    if around is not None and unnamed.seeded.any():
        keep = ~_beside_seeds(state, unnamed, around, frames, obj, frame, point)
        obj, frame, point = obj[keep], frame[keep], point[keep]
    named = len(obj)
    u, f_u = np.nonzero(unnamed.point >= 0)
    obj, frame, point = np.r_[obj, len(state.position) + u], np.r_[frame, f_u + 1], np.r_[point, unnamed.point[u, f_u]]
    offsets = np.cumsum([0] + [len(c) for c in frames])
    location = np.concatenate(frames)[offsets[frame - 1] + point] if len(point) else np.zeros((0, 3))
    template_cost = np.zeros(len(obj))
    template_cost[:named] = gating.shape_weight * _shape_deviation(state, guide, obj[:named], frame[:named], location[:named])
    if unnamed.n_objects:
        template_cost[named:] = _typical_shape(template_cost[:named], obj[:named], frame[:named], guide)
    likelihood = (marker_likelihood(state, guide, frames, obj[:named], frame[:named], location[:named], unnamed)
                  if gating.likelihood else None)
    if likelihood is None:
        off_prediction = lengths(location - guide.predicted[frame - 1, obj])
        sigma = gating.prediction_sigma_mm + gating.prediction_sigma_growth_mm * guide.unseen[frame - 1, obj]
        template_cost += gating.prediction_weight * np.minimum(off_prediction / sigma, gating.prediction_cap_sigmas)
    candidates = WindowCandidates(
        template_location=np.vstack([state.position, unnamed.template_location]),
        template_occluded=np.r_[~state.visible, ~unnamed.seeded], n_frames=len(frames),
        object=obj, frame=frame, location=location,
        template_cost=template_cost,
        resources=_window_resources(frames, point_resources)[offsets[frame - 1] + point],
        occlusion_location=np.concatenate([guide.predicted.transpose(1, 0, 2),
                                           np.repeat(unnamed.template_location[:, None], len(frames), axis=1)]),
        motion=np.concatenate([expected_steps(guide, gating.step_median_frames).transpose(1, 0, 2), unnamed.motion]),
        likelihood=likelihood,
    )
    return CloudWindow(candidates=candidates, frame=frame, point=point, guide=guide)


def _beside_seeds(state: MarkerState, unnamed: UnnamedChains, around: WindowSurround, frames: list[np.ndarray],
                  obj: np.ndarray, frame: np.ndarray, point: np.ndarray) -> np.ndarray:
    """True for the named candidates on a seeded unnamed track's points whose marker was seen
    apart from it: at the template, or where it was last seen (``around.coexisting``)."""
    u_seeded = np.flatnonzero(unnamed.seeded)
    apart = np.repeat(state.visible[:, None], len(u_seeded), axis=1)
    if around.coexisting is not None and len(around.template):
        k = cdist(unnamed.template_location[u_seeded], around.template).argmin(axis=1)
        apart |= around.coexisting[:, k]
    owner = np.full((len(frames), max(len(c) for c in frames) + 1), -1)
    rows = unnamed.point[u_seeded]
    f_s, c_s = np.nonzero(rows.T >= 0)
    owner[f_s, rows[c_s, f_s]] = c_s
    held = owner[frame - 1, point]
    return np.asarray((held >= 0) & apart[obj, np.maximum(held, 0)])


def _shape_deviation(
    state: MarkerState, guide: GuideTrack, obj: np.ndarray, frame: np.ndarray, location: np.ndarray
) -> np.ndarray:
    """Shape term per candidate: deviation from learned neighbour distances (see module doc)."""
    # (frame, neighbour) as one flat index, taken twice: a gather by two index arrays costs more
    at = (frame[:, None] - 1) * guide.predicted.shape[1] + state.neighbours[obj]  # (C, K)
    predicted = np.take(guide.predicted.reshape(-1, 3), at, axis=0)  # (C, K, 3)
    distance = lengths(location[:, None] - predicted)
    weight = guide.tracked.ravel()[at] / (state.distance_var[obj] + 1.0)
    if guide.carriers is not None:
        # A carried marker is judged by the rigid body carrying it: a pair learned while the
        # subject sat still (a lifting wrist and the thigh) that the carry found apart says nothing.
        carriers = guide.carriers[frame - 1, obj]  # (C, K)
        weight = weight * (carriers | ~carriers.any(axis=1, keepdims=True))
    deviation = np.minimum(np.abs(distance - state.distance_mean[obj]), SHAPE_CAP_MM)
    mean_deviation: np.ndarray = (weight * deviation).sum(axis=1) / np.maximum(weight.sum(axis=1), SHAPE_WEIGHT_FLOOR)
    return mean_deviation


def _typical_shape(template_cost: np.ndarray, obj: np.ndarray, frame: np.ndarray, guide: GuideTrack) -> float:
    """What a right label pays for its shape: over the markers seen the frame before, the
    median of each one's cheapest candidate per frame."""
    seen = guide.unseen[frame - 1, obj] == 0
    if not seen.any():
        return 0.0
    key = obj[seen] * (guide.unseen.shape[0] + 1) + frame[seen]
    order = np.lexsort((template_cost[seen], key))
    first = np.r_[True, np.diff(key[order]) != 0]
    return float(np.median(template_cost[seen][order][first]))


def _window_resources(frames: list[np.ndarray], point_resources: list[sp.csr_matrix] | None) -> sp.csr_matrix:
    """Resources of every point of the window, frames on the diagonal (no sharing across frames)."""
    if point_resources is None:
        return sp.identity(sum(len(c) for c in frames), format="csr")
    return sp.block_diag(point_resources, format="csr")
