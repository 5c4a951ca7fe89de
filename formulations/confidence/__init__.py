"""A confidence for every label of a window's answer (issue 13, item 5).

``label_confidence(problem, path)`` works on any formulation's answer: it needs only the
``WindowProblem`` and the chosen paths. ``margins`` finds, per object, frame and other
node, how much dearer the best reading through that node is (moving one or two objects);
``probability`` turns the margins into a probability under the objective read as a
negative log-likelihood, where the readings that put a label at the same place (a copied
point, ``same_place``) count for it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.margins import reading_margins
from formulations.confidence.probability import label_probability, nearest_alternative
from formulations.confidence.same_place import same_place
from formulations.window.problem import WindowProblem

CONFIDENCE_SCALE = 1.0  # cost units per nat: the window's costs are read as negative log-likelihoods
NEGLIGIBLE_NATS = 12.0  # alternatives dearer than this many nats are left out: each would move p by < 1e-5


@dataclass(frozen=True)
class LabelConfidence:
    """Per object and frame 1..M of a window.

    Attributes:
        probability: ``(N, M)`` p that the chosen label (node) is the right one.
        margin: ``(N, M)`` cost of the best reading that changes the label minus the
            chosen reading's (inf when none exists within ``NEGLIGIBLE_NATS``).
    """

    probability: NDArray[np.float64]
    margin: NDArray[np.float64]


def label_confidence(problem: WindowProblem, path: NDArray[np.intp], scale: float = CONFIDENCE_SCALE) -> LabelConfidence:
    """The confidence of every label of ``path`` (``(N, M)`` nodes) in ``problem``."""
    margin, grid = reading_margins(problem, np.asarray(path, dtype=np.intp), NEGLIGIBLE_NATS * scale)
    chosen, same = grid.chosen[:, 1:-1], same_place(problem, grid)
    return LabelConfidence(label_probability(margin, chosen, same, scale), nearest_alternative(margin, chosen, same))
