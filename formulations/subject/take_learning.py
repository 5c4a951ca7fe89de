"""Segments the model never finds at the start of a take, learned from the take (Ringer & Lasenby 2004).

A model from a static trial can miss a segment of the dynamic take altogether: a marker
placed or held otherwise (acromia 342 mm apart standing, 419 mm walking) moves its
constellation beyond any tolerance noise and skin allow, so the segment has no hypothesis,
and segments hung from it by joints are never placed either. The take has the segment's
true constellation: its markers are points no named marker explains, that keep their
distances frame after frame. Over the look-ahead frames (the first window: what the labeler
looks ahead anyway):

1. A segment of which identification names fewer than two markers (``FOUND_WITH``; a pair:
   both) in more than half of them is unfound. One marker named alone is no finding: it can
   sit on a joint's sphere wherever the segment is turned.
2. In a look-ahead frame f where an unfound segment is jointed to a posed one (a segment of
   three or more markers identification placed, or a placed pair jointed to a posed segment,
   whose joint centre is its third point: a forearm hung from an upper-arm pair), it is read
   from the free points with no distance tolerance (``loose_read``) and relearned from that
   reading (``segment_relearn``) unless the reading's RMS residual to the model's
   constellation exceeds ``LOOSE_RMS_MM``: markers placed otherwise than in the model move a
   few cm (gait2354's acromia, 76 mm wider apart in the walk: 38 mm RMS), while on CMU 135_02
   the readings that took other markers' points (a head and a thigh marker for an upper-arm
   pair) were 54-430 mm off, and once learned cost up to 16 points there.
3. The relearned model is kept when identification finds the segment (step 1) in more of
   the other look-ahead frames than the model did in all of them: a rigid constellation
   of the take, that explains points the model left unexplained. A reading of ghosts, or of
   markers of different segments, does not keep its distances and is not found again.
   Otherwise the next frame is tried.

Once found, a relearned segment can be the posed neighbour another unfound one is read
against (an arm hung from a relearned torso), so the steps repeat until no segment is
learned; a segment is learned once. Segments identification finds in most look-ahead
frames are left as they are, and when it finds every segment in the first frame nothing is
learned at all. Counting a segment found on one marker named (before the bound on loose
readings) kept the learning off readings of other points, at the price of segments named on
one marker that were never learned; with the bound, two markers: 135_02 98.46 -> 98.57 %,
03_rolling 40.54 -> 43.19 % from their models, every other row of ``bench/model_start.py``
unchanged; posing through ``segment_poses`` (two joints pose a segment too) 03_rolling 45.95 %.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.subject.constellation import Pose
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import Identification, identify
from formulations.subject.loose_read import loose_read
from formulations.subject.model import SubjectModel
from formulations.subject.segment_pose import segment_poses
from formulations.subject.segment_relearn import relearned

Array = NDArray[np.float64]
FOUND_WITH = 2  # markers named for a segment to count as found
LOOSE_RMS_MM = 50.0  # markers placed otherwise than in the model: gait2354's acromia read at 38 mm; other points: 54-430


def learn_from_take(model: SubjectModel, frames: list[Array]) -> SubjectModel:
    """``model`` with the segments it does not find in ``frames`` (each ``(P, 3)``, mm) learned from them."""
    geometry = ModelGeometry.of(model)
    if not frames or _segments_named(geometry, identify(geometry, frames[0])).all():
        return model  # everything found at the start: nothing to learn (and no look-ahead cost)
    learned: set[int] = set()
    while True:
        found = [identify(geometry, points) for points in frames]
        count = np.sum([_segments_named(geometry, f) for f in found], axis=0)
        unfound = [s for s in np.argsort([-len(g.markers) for g in geometry.segments], kind="stable")
                   if 2 * count[s] <= len(frames) and s not in learned]
        step = _learn_one(model, geometry, frames, found, unfound, count)
        if step is None:
            return model
        model, s = step
        learned.add(s)
        geometry = ModelGeometry.of(model)


def _learn_one(model: SubjectModel, geometry: ModelGeometry, frames: list[Array], found: list[Identification],
               unfound: list[int], count: NDArray[np.int64]) -> tuple[SubjectModel, int] | None:
    """The model with the first unfound segment whose loose reading is confirmed, and that segment."""
    for f, (points, identified) in enumerate(zip(frames, found)):
        free = np.ones(len(points), bool)
        free[identified.point[identified.named]] = False
        poses = _poses(geometry, identified)
        for s in unfound:
            reading = loose_read(geometry, s, points, free, poses)
            if reading is None or reading.rms > LOOSE_RMS_MM:
                continue
            trial = relearned(model, s, reading, poses)
            others = [p for g, p in enumerate(frames) if g != f]
            if _named_in(ModelGeometry.of(trial), s, others, int(count[s])) > count[s]:
                return trial, s
    return None


def _named_in(geometry: ModelGeometry, s: int, frames: list[Array], beat: int) -> int:
    """In how many of ``frames`` identification names a marker of segment ``s`` (counting stops
    once ``beat`` is beaten or can no longer be)."""
    hits = 0
    for k, points in enumerate(frames):
        hits += int(_segments_named(geometry, identify(geometry, points))[s])
        if hits > beat or hits + len(frames) - 1 - k <= beat:
            break
    return hits


def _segments_named(geometry: ModelGeometry, found: Identification) -> NDArray[np.bool_]:
    """``(S,)`` segments with ``FOUND_WITH`` markers named (all of a pair's; a pose would be too
    strict a test: with it 135_02 and 03_rolling relearned segments that tracking labels well
    and lost 4-9 points)."""
    return np.array([found.named[segment.markers].sum() >= min(FOUND_WITH, len(segment.markers))
                     for segment in geometry.segments])


def _poses(geometry: ModelGeometry, found: Identification) -> dict[int, Pose]:
    """The pose of each segment identification placed (its placed markers are R u + d exactly)
    where that pose is determined (``segment_poses``): three or more markers, or a placed pair
    jointed to a posed segment, the joint centre its third point (a forearm hung from an
    upper-arm pair), outwards along the chain."""
    poses = segment_poses(geometry, found.placed[None])
    return {int(s): Pose(poses.rotation[0, s], poses.origin[0, s]) for s in np.flatnonzero(poses.posed[0])}
