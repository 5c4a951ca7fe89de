"""Where an occluded marker is: the rigid motion of its segment-mates since it was last seen.

For marker p occluded in frame f, last seen at frame a, with M the markers of its segment
seen both at a and at f (three or more), the Kabsch motion (R, c_a, c_f) of M from frame a
to frame f carries it:

    x_p(f) = R (x_p(a) - c_a) + c_f.

This keeps how the markers sit in this take (skin and placement differ from the takes the
model was fitted on by more than the model's spread, and on three close markers a few mm
tilt the pose of a far one by centimetres); only the grouping comes from the model. Where
fewer than three mates were seen at both frames, the segment's pose in frame f places the
marker at R_f u_p + d_f (``segment_poses``: its labeled markers, else the joint chain).
The reference of a marker not seen in the window is its state's anchor (where it and its
neighbours were when last seen).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rigid import rigid_transform
from formulations.markers.state import MarkerState
from formulations.subject.geometry import ModelGeometry
from formulations.subject.segment_pose import segment_poses

Array = NDArray[np.float64]


def segment_fill(geometry: ModelGeometry, state: MarkerState, positions: Array, within: float) -> Array:
    """``(M, N, 3)`` fill of the window ``positions`` ``(M, N, 3)`` (NaN: occluded) after the
    template ``state``; NaN where the model carries nothing (singles, unposed segments)."""
    frames = len(positions)
    seen = np.asarray(np.isfinite(positions).all(axis=2), dtype=bool)
    index = np.arange(frames)[:, None]
    latest = np.maximum.accumulate(np.where(seen, index, -1), axis=0)  # last seen frame, -1: before the window
    filled = segment_poses(geometry, positions, within).place(geometry)
    filled[seen] = np.nan
    reference = np.where(state.anchor_valid[:, :, None], state.anchor_neighbours, np.nan)
    before = np.full((len(state.position), len(state.position), 3), np.nan)  # (N, N, 3) per marker: its anchor frame
    np.put_along_axis(before, state.neighbours[:, :, None], reference, axis=1)
    before[np.arange(len(before)), np.arange(len(before))] = state.anchor
    for segment in geometry.segments:
        m = segment.markers
        frame, own = np.nonzero(~seen[:, m])
        if len(m) < 4 or not len(frame):
            continue
        marker, last = m[own], latest[frame, m[own]]
        source = np.where((last >= 0)[:, None, None], positions[np.maximum(last, 0)][:, m], before[marker][:, m])
        at = np.where((last >= 0)[:, None], positions[np.maximum(last, 0), marker], state.anchor[marker])
        target = positions[frame][:, m]
        usable = np.isfinite(source).all(axis=2) & np.isfinite(target).all(axis=2) & (m[None] != marker[:, None])
        enough = usable.sum(axis=1) >= 3
        if not enough.any():
            continue
        rotation, c_a, c_f = rigid_transform(np.nan_to_num(source[enough]), np.nan_to_num(target[enough]),
                                             usable[enough].astype(float))
        filled[frame[enough], marker[enough]] = np.einsum("qij,qj->qi", rotation, at[enough] - c_a) + c_f
    return filled
