"""Objects that come and go: births from unexplained detections, deaths after occlusion.

Jiang's network tracks a fixed set of objects; MOT needs them to come and go. The rule
(Jiang Sec. II-E inserts "a consistent object which is not on the track" into the object
list; here consistency is a chain of boxes):

- **Birth.** After a window is solved, the detections of its frames t0..t0+M that no object
  explains (took, or holds a box in the same conflict set), and, with ``returns_compete``,
  those an object took after a miss in or before the window (``reentries``), are linked frame
  to frame (an optimal assignment on IoU, pairs with IoU >= ``link_iou``, consecutive frames
  only). A chain of at least ``min_hits`` boxes that starts in the window is a new object,
  placed at the chain's first box with the chain's fitted velocity and mean histogram
  (``born``), and the window is solved again with it: from its first frame on, the new
  object competes for boxes with the others in the window optimisation, and the chain only
  says where it starts. A new object that takes no box when the window is solved again is dropped.
- **Returns against newcomers** (``returns_compete``). A chain holding boxes a lost object
  took after a miss is either that object back or a new person. The two are weighed by the
  chain's likelihood under each, one box at a time from the boxes before it, with the prior
  odds of a return and a birth learned from the take (``returns.newcomer_wins``,
  ``births.BirthRates``). If the object wins, the chain is not a new object; if the
  newcomer wins, it is one, and the object may not take the chain's boxes when the window is
  solved again. Without this test a lost object often takes a newcomer inside its widening
  gate: the window sums one costly jump with the cheap steps after it, and nothing else is on
  offer. Such a chain runs on past the window, as many frames as the window has after its
  template (into frames not solved yet, whose boxes are all free): a newcomer a lost object
  took in the window's last frames is not offered again, since in the next window those
  boxes are the object's, and a longer chain is more evidence for the test. A chain of
  boxes nobody took needs ``min_hits`` of them in the window and is cut at its end (it is
  offered again from the next window's template); a window shorter than ``min_hits`` frames
  (window 2) lets it run to ``min_hits`` frames after the template instead.
- **Death.** An object unseen for more than ``max_occluded`` frames leaves. One whose
  prediction has crossed the image border leaves sooner, after ``border_occluded`` frames:
  a person walking out of the picture is not behind someone. In the window itself an
  object that goes into occlusion pays c_a + c_b per frame and the sink costs the same as
  an occlusion node, so the sink never decides a death on its own: the frame count does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from formulations.boxes import kalman
from formulations.boxes.geometry import iou
from formulations.boxes.objects import BoxObjects, fitted_velocity

Array = NDArray[np.float64]
Ints = NDArray[np.int_]


@dataclass(frozen=True)
class Lifecycle:
    """When objects are born and when they leave (see the module docstring).

    Attributes:
        min_hits: Boxes in a chain of unexplained detections that make a new object.
        link_iou: Smallest IoU between consecutive boxes of a chain.
        max_occluded: Frames unseen after which an object leaves.
        border_occluded: Frames unseen after which an object predicted across the image border leaves.
        returns_compete: Test the chains a lost object took after a miss against a newcomer
            (module docstring). On by default: on the sequences the box costs were chosen on
            (TUD-Campus, MOT17-02) it gains HOTA and IDF1 (MOT17-02: 0.476 -> 0.481, 0.521 ->
            0.537) at the same ID switches (docs/boxes.md).
    """

    min_hits: int = 3
    link_iou: float = 0.3
    max_occluded: int = 30
    border_occluded: int = 5
    returns_compete: bool = True

    def __post_init__(self) -> None:
        if self.min_hits < 1 or not 0 < self.link_iou <= 1 or self.border_occluded < 0 or self.max_occluded < 0:
            raise ValueError("lifecycle: min_hits >= 1, 0 < link_iou <= 1, occlusion limits >= 0")

    def chains(self, frame: Ints, boxes: Array, free: NDArray[np.bool_]) -> list[Ints]:
        """Chains (detection indices in frame order) of ``min_hits`` or more free boxes."""
        closed: list[list[int]] = []
        open_chains: list[list[int]] = []
        for f in np.unique(frame[free]):
            index = np.flatnonzero(free & (frame == f))
            alive = [c for c in open_chains if frame[c[-1]] == f - 1]
            closed += [c for c in open_chains if frame[c[-1]] != f - 1]
            overlap = iou(boxes[[c[-1] for c in alive]].reshape(-1, 4), boxes[index])
            rows, cols = linear_sum_assignment(-overlap)
            linked = overlap[rows, cols] >= self.link_iou
            for r, c in zip(rows[linked], cols[linked]):
                alive[r].append(int(index[c]))
            taken = set(cols[linked].tolist())
            closed += [alive[r] for r in range(len(alive)) if r not in set(rows[linked].tolist())]
            open_chains = [alive[r] for r in rows[linked]] + [[int(index[c])] for c in range(len(index)) if c not in taken]
        return [np.array(c) for c in closed + open_chains if len(c) >= self.min_hits]

    def window_chains(self, frame: Ints, boxes: Array, free: NDArray[np.bool_], returned: NDArray[np.bool_],
                      template_frame: int, n_frames: int, last_frame: int) -> list[Ints]:
        """Chains of ``free`` boxes starting in frames t0..t0+M (``template_frame``, ``n_frames``)
        with ``min_hits`` boxes there (cut at the window's end, or ``lookahead`` frames after the
        template when the window is shorter than ``min_hits``), or, if they hold a ``returned``
        box, ``min_hits`` boxes up to ``n_frames`` frames past the window (no further than
        ``last_frame``; module doc)."""
        end = template_frame + n_frames
        # A window shorter than min_hits (window 2: template + 1) could never hold a chain:
        # the chain is then cut at the look-ahead, but still starts in the window.
        cut = min(template_frame + self.lookahead(n_frames), last_frame)
        reach = max(min(end + n_frames, last_frame), cut) if returned.any() else cut
        found = self.chains(frame, boxes, free & (frame >= template_frame) & (frame <= reach))
        straddling = [c for c in found if frame[c[0]] <= end and returned[c].any()]
        inside = [c[frame[c] <= cut] for c in found if not returned[c].any() and frame[c[0]] <= end]
        return straddling + [c for c in inside if len(c) >= self.min_hits]

    def lookahead(self, n_frames: int) -> int:
        """Frames after the template a window's chains may use: its own ``n_frames``, or
        ``min_hits - 1`` when that is more (so a chain of ``min_hits`` boxes fits)."""
        return max(n_frames, self.min_hits - 1)

    def leaving(self, objects: BoxObjects, now: int, image: Array) -> NDArray[np.bool_]:
        """True for the objects that leave at frame ``now``; ``image`` is (x1, y1, x2, y2)."""
        gap = now - objects.last_seen
        predicted = objects.box  # the objects are at frame ``now``
        outside = (predicted[:, :2] < image[:2]).any(axis=1) | (predicted[:, 2:] > image[2:]).any(axis=1)
        result: NDArray[np.bool_] = (gap > self.max_occluded) | (outside & (gap > self.border_occluded))
        return result


def reentries(last_seen: Ints, taken: Ints, template_frame: int) -> Ints:
    """Detections (rows of ``taken``'s values) each object took after a miss: from its first
    box after an occluded frame of the window, or from its first box if it was not seen at
    the template; ``taken`` is ``(N, M)`` as in ``objects.advance``, ``last_seen`` ``(N,)``."""
    missed = (np.cumsum(taken < 0, axis=1) > 0) | (last_seen < template_frame)[:, None]
    result: Ints = taken[missed & (taken >= 0)]
    return result


def born(chains: list[Ints], frame: Ints, boxes: Array, histograms: Array | None, first_ident: int,
         template_frame: int) -> BoxObjects:
    """New objects from chains, numbered from ``first_ident``, posed to enter the window again.

    Each starts a Kalman state (``kalman.start``) at its chain's first box, frame s, with the
    chain's fitted velocity, moved back to the template frame t0 along that velocity; it is
    last seen at s if s = t0, else at s - 1, so that the window, solved again with it, can
    take its first box at s and none before.
    """
    n = len(chains)
    hist = None if histograms is None else np.array([histograms[c].mean(axis=0) for c in chains]).reshape(n, -1)
    velocity = kalman.measurement(np.array([fitted_velocity(frame[c], boxes[c]) for c in chains]).reshape(n, 4))
    first = np.array([frame[c[0]] for c in chains], dtype=int)
    z = kalman.measurement(np.array([boxes[c[0]] for c in chains]).reshape(n, 4))
    mean, covariance = kalman.start(z - (first - template_frame)[:, None] * velocity, velocity)
    last_seen = np.where(first == template_frame, first, first - 1)
    return BoxObjects(np.arange(first_ident, first_ident + n), mean, covariance, last_seen, hist)
