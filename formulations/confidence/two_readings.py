"""One label's confidence from two labelings of the take (``service.labeling.second_pass``).

The two passes differ only in the distance spreads they start from, and each pass's
confidence is conditional on its own: a second pass from the take's wider spreads doubts
right labels the first was sure of (CMU 135_02 under the hard preset, seed 0: 2,522 right
labels doubtful in the second pass against 827 in the first). With c_k the kept pass's
confidence in its label of a marker in a frame and c_o the other pass's in its own:

- Both give the same label (the same point, or both occluded): the label's confidence is
  max(c_k, c_o). A doubt that only one set of spreads raises is the spreads' doubt, and the
  other reading of the same evidence has no such doubt.
- They differ: at most one is right (a marker holds one point or none), so
  p(kept right) <= 1 - p(other right), and the confidence is min(c_k, 1 - c_o).

Over 11 simulated runs (hard preset and matrix conditions where the second pass runs, lp-l1)
the doubtful share / recall went from the kept pass's own 0.267 / 0.947 to 0.227 / 0.975 on
135_02 (hard, seed 0), 0.131 / 0.742 -> 0.110 / 0.813 on 85_02 (hard, seed 1), 0.360 / 0.876
-> 0.317 / 0.906 on the tennis serve at 4 mm; the share rose on 2 of 11 runs (135_02 hard
seed 1 0.289 -> 0.307, with recall 0.917 -> 0.966), recall fell on 1 (03_rolling with
deletions 0.931 -> 0.876, with the share 0.321 -> 0.253).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def agreed_confidence(kept: Array, kept_label: NDArray[np.int64], other: Array, other_label: NDArray[np.int64]) -> Array:
    """The kept pass's confidences given the other pass's (module doc); all arrays one shape.

    Args:
        kept, other: Each pass's confidence in its label.
        kept_label, other_label: Each pass's label (point index, -1 occluded).
    """
    same = np.asarray(kept_label) == np.asarray(other_label)
    agreed: Array = np.where(same, np.maximum(kept, other), np.minimum(kept, 1.0 - np.asarray(other)))
    return agreed
