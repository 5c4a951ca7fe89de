"""An occluded marker carried by its segment's pose, through the marker state's own prediction.

``MarkerState`` predicts an unseen marker by the rigid motion of its neighbours since its
anchor frame (Kabsch from ``anchor_neighbours`` to where they are now, applied to ``anchor``).
A marker whose anchor frame saw three or more of its segment-mates follows only those
mates (the motion of nearby markers on other segments is not its motion). Otherwise, at a
template frame where the model poses the marker's segment (``segment_poses``: three
labeled markers, else the joint chain), the anchor is moved to that frame: the marker at
R u_p + d, each neighbour where it is seen (segment-mates unseen: where the pose puts them).
The state's prediction is then the segment's pose in every later frame, R(t) u_p + d(t),
estimated from the neighbours seen there, segment-mates weighing most (their distances vary
least), not a stale velocity. The other seen neighbours are followed too, with little
weight: a segment of three markers leaves a carried marker two mates, whose motion fixes
no rotation (about the line through them), and the state would only translate it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.markers.state import MarkerState
from formulations.subject.geometry import ModelGeometry
from formulations.subject.segment_pose import RIGID_WITHIN, segment_poses

Array = NDArray[np.float64]


def follow_segments(geometry: ModelGeometry, state: MarkerState) -> MarkerState:
    """``state`` (markers in ``geometry.names`` order) with its unseen markers anchored to their segments' poses."""
    seen = state.visible
    placed = segment_poses(geometry, np.where(seen[:, None], state.position, np.nan)[None], RIGID_WITHIN)
    placed = placed.place(geometry)[0]
    neighbours = state.neighbours
    segment = geometry.segment_of
    mate = (segment[neighbours] == segment[:, None]) & (segment[:, None] >= 0)
    anchored = ~seen & ((state.anchor_valid & mate).sum(axis=1) >= 3)
    carried = ~seen & ~anchored & np.isfinite(placed).all(axis=1) & mate.any(axis=1)
    state = replace(state, anchor_valid=np.where(anchored[:, None], state.anchor_valid & mate, state.anchor_valid))
    if not carried.any():
        return state
    now = np.where(seen[:, None], state.position, np.nan_to_num(placed))
    return replace(
        state,
        position=np.where(carried[:, None], placed, state.position),
        anchor=np.where(carried[:, None], placed, state.anchor),
        anchor_neighbours=np.where(carried[:, None, None], now[neighbours], state.anchor_neighbours),
        anchor_valid=np.where(carried[:, None], mate | seen[neighbours], state.anchor_valid),
        # Anchored anew, on the pose: what was carried at the old anchor says nothing of this one.
        anchor_carried=np.where(carried[:, None], False, state.anchor_carried),
    )
