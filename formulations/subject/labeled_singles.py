"""Markers a labeled frame names that the subject model lacks, added to the model as singles.

A model fitted on frames where a marker was never seen (a marker placed later, a virtual
joint centre a lab exports with the take) has no place for it, and labeling from the model
would drop the user's label. Labeled in the start frame, it is added as a single measured
there: its distances to the ``nearest`` segment origins the frame poses (``segment_poses``),
with sd 0, so its tolerance is the marker radius r and identification names it only where
one point fits both distances that closely. The tracker follows it from its label, as it
follows any labeled marker.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.subject.geometry import ModelGeometry
from formulations.subject.model import SingleMarker, SubjectModel
from formulations.subject.segment_pose import segment_poses

Array = NDArray[np.float64]


def with_labeled_singles(model: SubjectModel, names: list[str], positions: Array, nearest: int = 2) -> SubjectModel:
    """``model`` with a single for each marker of ``names`` it lacks that ``positions`` ``(N, 3)``
    (mm, NaN: not labeled) labels; unchanged when the frame poses no segment to measure from."""
    geometry = ModelGeometry.of(model)
    lacking = [k for k, name in enumerate(names) if name not in geometry.names and np.isfinite(positions[k]).all()]
    if not lacking:
        return model
    poses = segment_poses(geometry, geometry.in_model_order(names, np.asarray(positions, dtype=float)[None]))
    posed = np.flatnonzero(poses.posed[0])
    if not len(posed):
        return model
    singles = []
    for k in lacking:
        reach = np.linalg.norm(poses.origin[0, posed] - positions[k], axis=1)
        near = np.argsort(reach)[:nearest]
        singles.append(SingleMarker(names[k], [geometry.segments[posed[i]].name for i in near],
                                    [round(float(reach[i]), 3) for i in near], [0.0] * len(near)))
    return replace(model, singles=[*model.singles, *singles])
