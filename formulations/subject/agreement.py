"""Which segments a frame's identification reads as the labels carried into it.

Identification (``identify``) reads each segment from the model alone. A near-planar
constellation fits as well turned half a revolution (a pelvis read upside down: left and
right exchanged), so a reading can differ from labels that tracking carried rightly. A
segment agrees when every seen marker the reading names is named at the point it holds.
Acquiring unseen markers from a reading that does not agree would make the carried labels
contradict the model, and recovery would then adopt the wrong pose for all of them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.state import MarkerState
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import Identification
from formulations.subject.recover import HELD_MM


def agreeing(
    geometry: ModelGeometry, state: MarkerState, points: NDArray[np.float64], found: Identification,
) -> NDArray[np.bool_]:
    """``(N,)`` markers whose segment's reading names every seen mate at its point (singles: True)."""
    segment_of = geometry.segment_of
    named = state.visible & found.named
    moved = np.zeros(len(segment_of), bool)
    moved[named] = np.linalg.norm(points[found.point[named]] - state.position[named], axis=1) > HELD_MM
    differing = np.unique(segment_of[moved & (segment_of >= 0)])
    agrees: NDArray[np.bool_] = (segment_of < 0) | ~np.isin(segment_of, differing)
    return agrees
