"""The window's likelihood terms for markers in a 3D cloud (``window.likelihood``).

Per marker n and frame the step residual's sd per axis is s_n, learned from the take as it
is labeled (``markers.motion``): s_n^2 is 6 sigma^2 + q_n^2, the take's noise and the
marker's own acceleration, as the labels so far teach it, or the burst variance the guide
track had before that frame when wider (a burst starts within a window; the guide's own
slow envelope is not used, it learns from unverified nearest-neighbour points). A marker
unseen for u frames is predicted by following its neighbours (``MarkerState.predict``)
with a per-axis sd s_u = sqrt(s_n^2 + g^2 u), g^2 the drift per frame learned from earlier
reappearances: an old prediction is wide, not wrong, and nothing caps the distance term,
so a marker's own point and its neighbour's never cost the same. Reappearing at r,
predicted at p:

    r_j = rho(|r - p| / s_u) + 3 log s_u + (3/2) log 2 pi - log P_D + log lambda_FA + K.

P_D and lambda_FA come from the window itself, through the guide track: P_D is the share
of marker-frames the guide found a point for (with a Beta(18, 2) prior: a window of
occlusions must not make occlusion free), lambda_FA the points the guide left over per
frame (at least ``MIN_CLUTTER``) over the volume of the window's points grown by
``CLUTTER_MARGIN_MM``. Both are clipped to where the logs stay sane.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.guide import GuideTrack
from formulations.markers.lengths import lengths
from formulations.markers.motion import MOTION_VAR_PRIOR_MM2
from formulations.markers.state import MarkerState
from formulations.markers.unnamed import UnnamedChains
from formulations.window.likelihood import CandidateLikelihood, step_loss

LOG_2PI_3D = 1.5 * np.log(2 * np.pi)
PRIOR_HITS, PRIOR_MISSES = 18.0, 2.0  # Beta prior on P_D: 0.9 from 20 pseudo marker-frames
MIN_CLUTTER = 0.5  # false alarms per frame assumed even when the guide explained every point
CLUTTER_MARGIN_MM = 100.0


def marker_likelihood(
    state: MarkerState, guide: GuideTrack, frames: list[np.ndarray],
    obj: np.ndarray, frame: np.ndarray, location: np.ndarray, unnamed: UnnamedChains,
) -> CandidateLikelihood:
    """The likelihood terms of every named candidate (object ``obj``, window frame ``frame``,
    at ``location``), then of every ``unnamed`` object's (objects N.., module ``unnamed``: the
    step sd of a typical marker, no prediction, entry b, a free miss)."""
    n, m = len(state.position), len(frames)
    detection = _detection_probability(guide, n)
    spare, volume = _clutter(guide, frames)
    base = LOG_2PI_3D - np.log(detection) + np.log(spare / volume)
    step_var = np.maximum(state.motion_var[obj], guide.burst_var[frame - 1, obj])
    step_var = np.where(state.velocity_known[obj], step_var, np.maximum(step_var, MOTION_VAR_PRIOR_MM2))
    step_sigma = np.sqrt(step_var)
    predicted_sigma = np.sqrt(step_var + state.drift_var[obj] * guide.unseen[frame - 1, obj])
    off = lengths(location - guide.predicted[frame - 1, obj]) / predicted_sigma
    reappear = step_loss(off) + 3 * np.log(predicted_sigma) + base
    offset = 3 * np.log(step_sigma) + base
    typical = np.full(int(np.count_nonzero(unnamed.point >= 0)), np.sqrt(np.median(state.motion_var)))
    step_sigma, offset = np.r_[step_sigma, typical], np.r_[offset, 3 * np.log(typical) + base]
    reappear = np.r_[reappear, np.full(len(typical), np.log(spare / unnamed.births_per_frame()))]
    off = np.r_[off, np.zeros(len(typical))]
    miss = np.vstack([np.full((n, m), -np.log1p(-detection)), np.zeros((unnamed.n_objects, m))])
    # K: the lowest cost an observation can have (its residual 0) is lifted to 0.
    shift = -float(min(offset.min(initial=0.0), (reappear - step_loss(off)).min(initial=0.0)))
    miss = miss + shift
    return CandidateLikelihood(
        step_sigma=step_sigma, step_offset=offset + shift, reappear_cost=reappear + shift, miss_cost=miss,
    )


def _detection_probability(guide: GuideTrack, n: int) -> float:
    """Share of marker-frames the guide saw, Beta-prior smoothed, in [0.5, 0.99]."""
    seen = float((guide.unseen[1:] == 0).sum()) if len(guide.unseen) > 1 else 0.0
    total = float(n * (len(guide.unseen) - 1))
    return float(np.clip((seen + PRIOR_HITS) / (total + PRIOR_HITS + PRIOR_MISSES), 0.5, 0.99))


def _clutter(guide: GuideTrack, frames: list[np.ndarray]) -> tuple[float, float]:
    """False alarms per frame (points the guide did not take), and the padded volume they fall in (mm^3)."""
    counts = np.array([len(f) for f in frames], float)
    taken = (guide.unseen[1:] == 0).sum(axis=1) if len(guide.unseen) > 1 else np.zeros(0)
    spare = counts[: len(taken)] - taken
    per_frame = max(float(spare.mean()) if len(spare) else 0.0, MIN_CLUTTER)
    points = np.concatenate([f for f in frames if len(f)]) if any(len(f) for f in frames) else np.zeros((1, 3))
    extent = points.max(axis=0) - points.min(axis=0) + 2 * CLUTTER_MARGIN_MM
    return per_frame, float(np.prod(extent))
