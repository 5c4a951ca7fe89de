"""One window of box tracking posed as Jiang's network: candidates near each prediction.

Frame t0 is the template (Sec. II-E: windows overlap by it); frames t0+1..t0+M hold the
candidates. Every detection inside an object's gate around its Kalman forecast
(``BoxCostModel.gate_and_cost``) is one of its candidate nodes with location its corners
(Jiang's 4-vector p) in the object's heights, template cost g(s_n, v) and, as resources, the conflict sets it belongs to
(``conflicts.conflict_resources``): a detection is never taken twice, nor two boxes that
are one spatial location. An object not seen at t0 starts from its prediction with an
occluded template, so its first arc costs like leaving an occlusion. A detection a
newcomer has won from an object (``returns``) is barred from that object's candidates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from formulations.boxes import kalman
from formulations.boxes.conflicts import ConflictRule, conflict_resources
from formulations.boxes.costs import BoxCostModel, histogram_distance
from formulations.boxes.geometry import centre, height
from formulations.boxes.kalman import box_corners, corner_rates
from formulations.boxes.likelihood import DetectionRates, box_likelihood, clutter_volume
from formulations.boxes.objects import BoxObjects
from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


@dataclass(frozen=True)
class BoxWindow:
    """A window ready for ``build_window``: candidates, weights, layout, and which detection each candidate is.

    Attributes:
        candidates: The window's candidates.
        weights: Arc cost weights.
        layout_pairs: ``(P, 2)`` neighbouring objects.
        layout_weight: mu per pair.
        detection: ``(C,)`` index, into the detections handed in, of each candidate.
    """

    candidates: WindowCandidates
    weights: ArcCostWeights
    layout_pairs: Ints
    layout_weight: float
    detection: Ints


def box_window(
    objects: BoxObjects, template_frame: int, n_frames: int, frame: Ints, boxes: Array, histograms: Array | None,
    model: BoxCostModel, rule: ConflictRule, rates: DetectionRates | None = None, image: Array | None = None,
    barred: NDArray[np.bool_] | None = None,
) -> BoxWindow:
    """Pose frames ``template_frame+1 .. template_frame+n_frames`` for ``objects``.

    Locations are corners in units of each object's height at the template frame, so that
    lambda_2 and mu weigh a near and a far person alike.

    Args:
        objects: Objects alive at the template frame.
        template_frame: t0.
        n_frames: M.
        frame, boxes, histograms: The detections of frames t0+1..t0+M: frame, corners,
            histograms (None without frames).
        model: Gate and costs.
        rule: When two boxes conflict.
        rates: P_D and false alarms so far: price arcs as negative log-likelihoods
            (``formulations.boxes.likelihood``; the template term keeps only the histogram),
            or None for Jiang's weighted costs.
        image: ``(4,)`` the image rectangle (x1, y1, x2, y2), where false alarms fall; needed with ``rates``.
        barred: ``(N, K)`` True where object n may not take detection k (of those handed in).
    """
    frames = template_frame + np.arange(1, n_frames + 1)
    predicted, spread = objects.forecast(n_frames)  # (N, M, 4), (N, M, 4, 4)
    objs, dets, costs = [], [], []
    for m, f in enumerate(frames):
        index = np.flatnonzero(frame == f)
        inside, cost = model.gate_and_cost(predicted[:, m], spread[:, m], boxes[index])
        inside &= (f > objects.last_seen)[:, None]  # a newborn takes nothing before its first box
        if barred is not None:
            inside &= ~barred[:, index]
        n, b = np.nonzero(inside)
        objs.append(n)
        dets.append(index[b])
        costs.append(cost[n, b])
    obj, det = np.concatenate(objs).astype(int), np.concatenate(dets).astype(int)
    template_cost = np.concatenate(costs)
    likelihood = None
    if rates is not None:
        if image is None:
            raise ValueError("box likelihood costs need the image rectangle")
        log_clutter = float(np.log(rates.false_alarms_per_frame / clutter_volume(image, boxes)))
        likelihood = box_likelihood(objects, rates, log_clutter, predicted, spread, obj, frame[det] - template_frame,
                                    kalman.measurement(boxes[det]))
        template_cost = np.zeros(len(det))  # the forecast is in the reappear cost
    hist_dist = None
    if histograms is not None and objects.histogram is not None:
        hist_dist = histogram_distance(histograms[det], objects.histogram[obj])
        template_cost = template_cost + model.histogram * hist_dist
    unit = np.maximum(objects.mean[:, 3], 1.0)  # each object's height at t0
    resources = sp.csr_matrix(conflict_resources(rule, frame, boxes)[det])
    start = objects.box
    velocity = np.repeat((corner_rates(objects.mean) / unit[:, None])[:, None, :], n_frames, axis=1)
    candidates = WindowCandidates(
        template_location=start / unit[:, None],
        template_occluded=objects.last_seen < template_frame,
        n_frames=n_frames, object=obj, frame=frame[det] - template_frame, location=boxes[det] / unit[obj, None],
        template_cost=template_cost, resources=resources, occlusion_location=box_corners(predicted) / unit[:, None, None],
        motion=velocity, appearance=None if hist_dist is None or histograms is None else histograms[det],
        template_appearance=None if hist_dist is None else objects.histogram, likelihood=likelihood,
    )
    weights = ArcCostWeights(  # floats: integer weights would make the arc cost array integer
        appearance_change=float(model.histogram_change) if hist_dist is not None else 0.0,
        displacement=float(model.displacement), reappear=float(model.reappear), disappear=float(model.disappear),
        template_on_track=float(model.template_on_track),
    )
    return BoxWindow(candidates, weights, _neighbours(start, model) if model.layout > 0 else np.zeros((0, 2), int),
                     model.layout, det)


def _neighbours(start: Array, model: BoxCostModel) -> Ints:
    """Object pairs whose template centres lie within ``layout_reach`` mean heights."""
    c, h = centre(start), height(start)
    scale = 0.5 * (h[:, None] + h[None, :])
    near = np.linalg.norm(c[:, None] - c[None, :], axis=2) <= model.layout_reach * scale
    i, j = np.nonzero(np.triu(near, 1))
    return np.column_stack([i, j]).astype(int)
