"""Re-read from the model the segments whose labels contradict it, instead of carrying the error on.

At a template frame, segments whose seen markers no longer fit their constellation
(``contradicting``) are looked up again: the frame is identified from the model alone
(``identify``, passed in so that one identification serves every use), and a contradicting
segment takes that reading when it is sound (at least three of its markers named, each
within tau_p of where the model puts it), differs from the labels carried, and takes no
point held by a marker of a segment that fits. Its named markers are then seen at their identified points
(velocity unknown); its markers the reading leaves unnamed, and markers of other segments
that held one of the reclaimed points, become unseen and follow their segments until seen.
Where the reading cannot be taken, the segment's own points are assigned again in the order
that fits it (``reorder``): an exchange within the segment is undone without the frame's
identification, which can read a loose segment on its mirror image.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.markers.state import MarkerState
from formulations.subject.contradiction import contradicting
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import Identification
from formulations.subject.reorder import reordered
from formulations.subject.start_state import acquire

Array = NDArray[np.float64]
HELD_MM = 1e-6  # a seen marker's state position is the point it took, exactly


def recover(
    geometry: ModelGeometry, state: MarkerState, points: Array, identified: Callable[[], Identification],
) -> tuple[MarkerState, list[int]]:
    """``state`` with contradicting segments re-read from ``points`` ``(P, 3)``, and those segments.

    ``identified`` gives ``identify(geometry, points)``, called only when a segment contradicts.
    """
    seen = state.visible
    bad = np.flatnonzero(contradicting(geometry, np.where(seen[:, None], state.position, np.nan)))
    if not len(bad) or not len(points):
        return state, []
    found = identified()
    held = point_holders(state, points)  # (P,) marker holding each point, -1 none
    labels = np.where(seen[:, None], state.position, np.nan)
    take: list[int] = []
    at: list[Array] = []
    drop: list[int] = []
    repaired: list[int] = []
    for s in bad:
        markers = geometry.segments[s].markers
        named = markers[found.point[markers] >= 0]
        sound = len(named) >= 3 and bool((found.residual[named] <= geometry.tolerance[named]).all())
        holders = held[found.point[named]]
        others = holders[(holders >= 0) & ~np.isin(geometry.segment_of[np.maximum(holders, 0)], bad)]
        if not sound or (holders == named).all() or len(others):
            # a reading that takes points of segments that fit is no better than the labels;
            # the segment's own points may still fit it in another order
            if _reorder(geometry, int(s), labels, take, at, drop):
                repaired.append(int(s))
            continue
        repaired.append(int(s))
        take.extend(int(m) for m in named)
        at.extend(points[found.point[named]])
        drop.extend(int(m) for m in markers[found.point[markers] < 0])
        drop.extend(int(m) for m in holders if m >= 0 and geometry.segment_of[m] != s)
    if not repaired:
        return state, []
    chosen = np.array(take, dtype=np.int64)
    state = acquire(state, chosen, np.array(at))
    lost = np.zeros(len(seen), bool)
    lost[np.array(drop, dtype=np.int64)] = True
    lost[chosen] = False
    return replace(state, unseen=np.where(lost, np.maximum(state.unseen, 1), state.unseen),
                   streak=np.where(lost, 0, state.streak), seen_at=np.where(lost[:, None], np.nan, state.seen_at)), repaired


def _reorder(geometry: ModelGeometry, segment: int, labels: Array, take: list[int], at: list[Array], drop: list[int]) -> bool:
    """Queue the segment's own points in the order that fits it (``reorder``); False if none does."""
    markers = geometry.segments[segment].markers
    order = reordered(geometry, segment, labels)
    if order is None:
        return False
    holding = markers[np.isfinite(labels[markers]).all(axis=1)]
    take.extend(int(m) for m in order)
    at.extend(labels[holding])
    drop.extend(int(m) for m in holding if m not in order)
    return True


def point_holders(state: MarkerState, points: Array) -> NDArray[np.int64]:
    """``(P,)`` the seen marker whose state position is each point, -1 for none."""
    held = np.full(len(points), -1, dtype=np.int64)
    seen = np.flatnonzero(state.visible)
    if not len(seen):
        return held
    gap = np.linalg.norm(points[:, None] - state.position[seen][None], axis=2)
    hit = gap.min(axis=1) <= HELD_MM
    held[hit] = seen[gap.argmin(axis=1)[hit]]
    return held
