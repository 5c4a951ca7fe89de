"""Carry the marker state one frame on from the markers ``per_camera_locate`` placed.

A marker seen by two or more agreeing cameras is seen: position and velocity are
measured (``MarkerState.advance``). One view fixes two of the marker's three coordinates:
the point X of the ray nearest the prediction differs from it only across the ray. It is
not counted as seen, since a velocity measured along the unseen depth would drift, but
it re-anchors the marker: X becomes its position and its anchor, with its neighbours'
positions this frame, so the rigid motion of the neighbours carries it on from X rather
than from where two cameras last saw it. A hand tracked by one camera for seconds then
stays on that camera's ray instead of drifting off with its neighbours' motion, and a
second camera finds it in its gate when it comes back.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.cameras.per_camera.locate import LocatedMarkers
from formulations.markers.state import MarkerState


def advance_state(state: MarkerState, located: LocatedMarkers) -> MarkerState:
    """The state one frame later, seen where two or more views agree, re-anchored where one does."""
    seen = located.n_views >= 2
    after = state.advance(located.point, seen)
    single = np.flatnonzero(located.n_views == 1)
    if len(single) == 0:
        return after
    position, anchor = after.position.copy(), after.anchor.copy()
    anchor_neighbours, anchor_valid = after.anchor_neighbours.copy(), after.anchor_valid.copy()
    position[single] = anchor[single] = located.point[single]
    anchor_neighbours[single] = after.position[state.neighbours[single]]
    anchor_valid[single] = seen[state.neighbours[single]]
    anchor_carried = after.anchor_carried.copy()
    anchor_carried[single] = False  # a new anchor: what was carried at the old one says nothing of it
    return replace(after, position=position, anchor=anchor, anchor_neighbours=anchor_neighbours, anchor_valid=anchor_valid,
                   anchor_carried=anchor_carried)
