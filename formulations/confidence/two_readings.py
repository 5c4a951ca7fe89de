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

Measured (``bench/cloud_accuracy.py --seeds 3 --frames 400 --formulations lp-l1 --scenario
configs/scenarios/hard.toml --recordings cmu-85_02 cmu-135_02 numediart-rolling``), doubtful
share / recall of the kept labels: 85_02 12.85 % / 0.897 -> 12.80 % / 0.946, 135_02 19.22 % /
0.900 -> 17.29 % / 0.927, 03_rolling 44.78 % / 0.951 -> 45.78 % / 0.959; 85_02 under the
issue's scenario, seeds 0-5, 1.94 % / 0.964 -> 1.91 % / 0.964. The price: the real tennis
serve's labels (99.92 % right) are 5.0 % doubtful instead of 3.3 %, where the first pass read
them otherwise and was sure of it.
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
