"""The confidence a result reports for each label: the window's probability calibrated
(``formulations.confidence.calibration``), the user's first frame sure, and a lone label (one
frame seen amid an occlusion, ``formulations.confidence.lone``) no surer than lone labels are
right."""

from __future__ import annotations

import numpy as np

from formulations.confidence.calibration import LABEL_CALIBRATION
from formulations.confidence.lone import lone_labels
from formulations.markers.shape_breaks import ShapeBreak
from service.io.recording import LabeledTrajectories
from service.labeling.shape_doubt import shape_doubted
from service.labeling.stats import frames_listed

# The reported confidence of a lone label: of those on the real takes relabeled by ``track``
# (``bench/real_takes.py``'s starts) where the file labels the marker, 171 of 193 were right,
# 89 % (44 more took a point the file names for no marker); under the simulated scenarios
# far fewer (2 of 96 under the hard preset; formulations/confidence/lone.py).
LONE_CONFIDENCE = 0.89


def reported(labels: LabeledTrajectories) -> LabeledTrajectories:
    """``labels`` with their confidences as reported (module doc), in place."""
    if labels.confidence.size:
        labels.confidence = LABEL_CALIBRATION(labels.confidence)
        labels.confidence[0] = 1.0  # the user labeled it
        lone = lone_labels(~labels.occluded)
        labels.confidence[lone] = np.fmin(labels.confidence[lone], LONE_CONFIDENCE)
    return labels


def as_reported(labels: LabeledTrajectories) -> tuple[LabeledTrajectories, list[ShapeBreak]]:
    """``labels`` with the confidence a result reports (``reported``, then capped inside the
    shape breaks, ``shape_doubt``), and the breaks; ``labels``' own confidences are replaced."""
    return shape_doubted(reported(labels))


def lone_sightings(names: list[str], occluded: np.ndarray) -> dict[str, list[int]]:
    """Per marker that has any, the first frames (from 0) where it was seen alone amid an
    occlusion (``stats.frames_listed``): its lone labels, reported doubtful."""
    return frames_listed(names, lone_labels(~np.asarray(occluded, dtype=bool)))
