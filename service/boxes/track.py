"""Track the boxes of one camera over a sequence, window by window (Jiang Sec. II-E).

Windows of ``window`` frames overlap by one frame, the template. For each window:

1. the objects alive at its template frame t0 get their candidates in frames t0+1..t0+M
   (``formulations.boxes.candidates``), the window is built (``formulations.window``) and
   solved by the chosen formulation (``lp-l1``, ``ilp``, ``nn-hungarian``, ...: any name
   ``formulations.get_formulation`` knows, so every one sees the same costs);
2. each object's taken boxes become its track; its Kalman state is filtered through them
   and predicted through its occlusions, and its template histogram moves on
   (``formulations.boxes.objects.advance``);
3. the detections no object explains (neither taken nor in the conflict set of a taken
   box) are chained into new objects, and the window is solved again with them; a new
   object that takes no box there is dropped; objects unseen too long leave
   (``formulations.boxes.lifecycle``). With ``Lifecycle(returns_compete=True)`` a chain an
   object took after a miss is weighed as its return against a newcomer by the chain's
   filtered likelihood under each and the birth and return rates learned so far
   (``formulations.boxes.returns``, ``formulations.boxes.births``); a newcomer that wins is
   a new object, and the window is solved again with the lost object barred from its boxes.

With ``formulation="nn-hungarian"`` the same loop runs frame-by-frame optimal assignment on
the same costs: SORT's association (Hungarian, gated) on the same Kalman forecast, which,
unlike SORT's, is filtered once per window rather than once per frame.

Public entry point (also used for people seen by several cameras, one call per camera):

    track_boxes(detections, formulation="lp-l1", window=5, histograms=None) -> BoxTracking
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from formulations import build_window, get_formulation
from formulations.boxes.births import BirthRates
from formulations.boxes.candidates import box_window
from formulations.boxes.conflicts import ConflictRule, conflict_resources, distinct_chains
from formulations.boxes.costs import BoxCostModel
from formulations.boxes.geometry import corners
from formulations.boxes.lifecycle import Lifecycle, born, reentries
from formulations.boxes.likelihood import DetectionRates, clutter_volume
from formulations.boxes.objects import BoxObjects, advance
from formulations.boxes.returns import tested_chains
from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation
from formulations.window.build import taken_candidates
from service.boxes.detections import BoxDetections, BoxTracks
from service.errors import InputError

HISTOGRAM_RATE = 0.2  # how fast a template histogram follows the taken boxes


@dataclass(frozen=True)
class BoxTracking:
    """What a tracking run returns: the tracks and how the windows went.

    Attributes:
        tracks: The tracked boxes.
        windows: Windows solved (windows without any object are not solved).
        integral_windows: Windows whose paths carry an optimality certificate.
        seconds: Wall time of the run.
        bounded_windows: Windows with any proven bound (none for a heuristic formulation).
    """

    tracks: BoxTracks
    windows: int
    integral_windows: int
    seconds: float
    bounded_windows: int = 0


def track_boxes(
    detections: BoxDetections,
    formulation: str | Formulation = "lp-l1",
    window: int = 5,
    histograms: np.ndarray | None = None,
    model: BoxCostModel = BoxCostModel(),
    rule: ConflictRule = ConflictRule(),
    lifecycle: Lifecycle = Lifecycle(),
    likelihood: bool = False,
) -> BoxTracking:
    """Track ``detections`` (one camera) and number the tracks 1, 2, ... in order of birth.

    Args:
        detections: Boxes per frame.
        formulation: A formulation name or instance (see ``markerflow formulations``).
        window: Frames per window, template included (>= 2).
        histograms: ``(K, H)`` normalised histogram per detection row, or None.
        model, rule, lifecycle: Costs and gate, conflict sets, births and deaths.
        likelihood: Price arcs as negative log-likelihoods with P_D and false alarms learned
            window by window (``formulations.boxes.likelihood``), else Jiang's weighted costs
            (``model``'s constants). Off by default: on MOT17 it lets the window's look-ahead
            carry lost objects onto other people's boxes (docs/boxes.md).

    Raises:
        InputError: A window shorter than 2, an unknown formulation, histograms of the wrong shape.
    """
    start = time.perf_counter()
    solver = _formulation(formulation)
    if window < 2:
        raise InputError(f"window must be at least 2 frames (a template and one new frame), got {window}")
    if histograms is not None and histograms.shape[0] != len(detections.frame):
        raise InputError(f"{histograms.shape[0]} histograms for {len(detections.frame)} detections")
    frame, boxes = detections.frame.astype(int), corners(detections.box)
    conflicting = conflict_resources(rule, frame, boxes)  # symmetric: row k is O(k), what taking k explains
    image = _image(detections, boxes)
    volume = clutter_volume(image, boxes)  # where a new object may appear: image x box sizes
    objects = BoxObjects.empty(None if histograms is None else histograms.shape[1])
    owner = np.zeros(len(frame), dtype=int)  # track id of each detection, 0 = none
    rates = DetectionRates() if likelihood else None
    births = BirthRates()
    windows = integral = bounded = 0
    t0, next_ident = 1, 1
    while t0 < detections.n_frames:
        m = min(window - 1, detections.n_frames - t0)
        inside = (frame > t0) & (frame <= t0 + m)
        posing = _Posing(t0, m, frame, boxes, histograms, model, rule, rates, image)
        before = objects
        taken = np.zeros((0, m), int)
        if objects.n_objects:
            objects, taken, certified = _solve(solver, before, posing, owner)
            windows, integral, bounded = windows + 1, integral + certified[0], bounded + certified[1]
        old, born_after = before.n_objects, 0
        unclaimed, returned = owner.copy(), np.zeros(len(frame), bool)
        if lifecycle.returns_compete:  # a lost object's chain: a return or a newcomer
            returned[reentries(before.last_seen, taken, t0)] = True
            unclaimed[returned] = 0
        chains = distinct_chains(lifecycle.window_chains(frame, boxes, ~_explained(unclaimed, conflicting), returned,
                                                         t0, m, detections.n_frames), conflicting)
        barred: list[tuple[int, np.ndarray]] = []
        if lifecycle.returns_compete:
            chains, barred = tested_chains(chains, before, owner, frame, boxes, t0, volume, births.newcomer_cost)
        if chains:
            new = born(chains, frame, boxes, histograms, next_ident, t0)
            starts = np.array([frame[c[0]] for c in chains])
            owner[[c[0] for c in chains if frame[c[0]] == t0]] = new.ident[starts == t0]
            owner[inside] = 0  # the window again, with the new objects competing from their first box
            before = before.joined(new)
            objects, taken, certified = _solve(solver, before, posing, owner, barred)
            windows, integral, bounded = windows + 1, integral + certified[0], bounded + certified[1]
            kept = (starts == t0) | (taken[old:] >= 0).any(axis=1)
            keep = np.r_[np.ones(old, bool), kept]
            objects, next_ident = _named(objects.subset(keep), old, owner, next_ident)
            before, taken = before.subset(keep), taken[keep]
            born_after = int((kept & (starts > frame.min())).sum())
        if lifecycle.returns_compete:
            births = births.counted(born_after, m, before.last_seen, taken, t0, np.arange(before.n_objects) < old)
        if rates is not None:
            rates = _counted(rates, before, taken, t0, inside & ~_explained(owner, conflicting))
        objects = objects.subset(~lifecycle.leaving(objects, t0 + m, image))
        t0 += m
    tracked = np.flatnonzero(owner)
    tracks = BoxTracks(frame=frame[tracked], track_id=owner[tracked], box=detections.box[tracked],
                       confidence=detections.confidence[tracked], n_frames=detections.n_frames,
                       occluded=np.zeros(len(tracked), bool))
    return BoxTracking(tracks, windows, integral, time.perf_counter() - start, bounded)


@dataclass(frozen=True)
class _Posing:
    """What every solve of one window shares: its frames, the detections, costs and priors."""

    t0: int
    m: int
    frame: np.ndarray
    boxes: np.ndarray
    histograms: np.ndarray | None
    model: BoxCostModel
    rule: ConflictRule
    rates: DetectionRates | None
    image: np.ndarray


def _solve(
    solver: Formulation, objects: BoxObjects, posing: _Posing, owner: np.ndarray,
    barred: list[tuple[int, np.ndarray]] | None = None,
) -> tuple[BoxObjects, np.ndarray, tuple[bool, bool]]:
    """Solve one window; write each taken detection's owner; return the objects moved on, the
    ``(N, M)`` detection each took (-1 occluded) and the certificate: integral, and bounded
    at all (a formulation that proves no bound never is). ``barred``: (object row,
    detections) it may not take (``returns.tested_chains``)."""
    p = posing
    index = np.flatnonzero((p.frame > p.t0) & (p.frame <= p.t0 + p.m))
    hist = None if p.histograms is None else p.histograms[index]
    mask = None
    if barred:
        mask = np.zeros((objects.n_objects, len(index)), bool)
        for row, c in barred:
            mask[row, np.searchsorted(index, c[np.isin(c, index)])] = True
    posed = box_window(objects, p.t0, p.m, p.frame[index], p.boxes[index], hist, p.model, p.rule, p.rates, p.image,
                       mask)
    problem, node_candidate = build_window(posed.candidates, posed.weights, posed.layout_pairs, posed.layout_weight)
    solution = solver.solve(problem)
    taken = taken_candidates(node_candidate, solution.path, index[posed.detection])  # (N, M), -1 occluded
    for n in range(objects.n_objects):
        owner[taken[n][taken[n] >= 0]] = objects.ident[n]
    moved = advance(objects, p.t0, taken, p.boxes, p.histograms, HISTOGRAM_RATE)
    return moved, taken, (bool(solution.integral), bool(np.isfinite(solution.gap)))


def _named(objects: BoxObjects, old: int, owner: np.ndarray, next_ident: int) -> tuple[BoxObjects, int]:
    """Number the new objects kept (those after the first ``old``) ``next_ident``, ... in order,
    in ``objects`` and ``owner`` alike, so that dropped ones leave no gap; return the next free number."""
    kept = objects.ident[old:]
    final = np.zeros(int(kept.max(initial=next_ident - 1)) - next_ident + 1, dtype=int)
    final[kept - next_ident] = next_ident + np.arange(len(kept))
    mine = owner >= next_ident
    owner[mine] = final[owner[mine] - next_ident]
    return replace(objects, ident=np.r_[objects.ident[:old], final[kept - next_ident]]), next_ident + len(kept)


def _counted(rates: DetectionRates, objects: BoxObjects, taken: np.ndarray, t0: int, spare: np.ndarray) -> DetectionRates:
    """``rates`` plus one window: its object-frames after each object's template sighting, and its spare detections."""
    due = (t0 + 1 + np.arange(taken.shape[1]))[None, :] > objects.last_seen[:, None]
    hits = int((taken >= 0).sum())
    return rates.counted(hits, int(due.sum()) - hits, int(spare.sum()), taken.shape[1])


def _explained(owner: np.ndarray, conflicting: sp.csr_matrix) -> np.ndarray:
    """Detections taken by an object, or in the conflict set of one taken."""
    explained = owner > 0
    explained[conflicting[np.flatnonzero(owner)].indices] = True
    return explained


def _formulation(spec: str | Formulation) -> Formulation:
    try:
        return get_formulation(spec)
    except FormulationError as error:
        raise InputError(str(error)) from None


def _image(detections: BoxDetections, boxes: np.ndarray) -> np.ndarray:
    """The image rectangle (x1, y1, x2, y2): from seqinfo.ini, else the extent of all the boxes."""
    if detections.image_size is not None:
        return np.array([0.0, 0.0, *detections.image_size])
    if len(boxes) == 0:
        return np.array([0.0, 0.0, 1.0, 1.0])
    return np.r_[np.minimum(boxes[:, :2].min(axis=0), 0.0), boxes[:, 2:].max(axis=0)]
