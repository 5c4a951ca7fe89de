"""Segments whose labeled markers no longer fit their constellation.

With three or more labeled markers a segment is posed by Kabsch (``segment_poses``) and each
labeled marker p has a residual |R u_p + d - x_p|. A correct labeling leaves every residual
within the marker's tolerance tau_p = sigmas s_p + r (``ModelGeometry``); two markers of the
segment exchanged, or a ghost taken for one, leave residuals of the order of the distances
between markers. A segment contradicts the model when some residual exceeds ``factor`` tau_p:
its labels are then to be read again from the model, not carried on.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.subject.geometry import ModelGeometry
from formulations.subject.segment_pose import RIGID_WITHIN, segment_poses

Array = NDArray[np.float64]


def contradicting(geometry: ModelGeometry, positions: Array, factor: float = RIGID_WITHIN) -> NDArray[np.bool_]:
    """``(S,)`` segments of ``positions`` ``(N, 3)`` (NaN: not labeled) that contradict the model."""
    placed = segment_poses(geometry, positions[None]).place(geometry)[0]
    excess = np.linalg.norm(placed - positions, axis=1) > factor * geometry.tolerance
    own = [len(s.markers) >= 3 and np.isfinite(positions[s.markers]).all(axis=1).sum() >= 3 for s in geometry.segments]
    found: NDArray[np.bool_] = np.array([o and bool(excess[s.markers].any()) for o, s in zip(own, geometry.segments)])
    return found.astype(bool).reshape(len(geometry.segments))
