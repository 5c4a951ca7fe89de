"""Lone labels: a marker labeled in one frame with no label in the frames before and after.

A window's confidence is the margin of its reading over the best reading that changes the
label. A marker lost in an occlusion that takes a point for one frame and loses it again has
no step before or after to be judged by: only its prediction, which has drifted while it was
unseen, prices the point, and against a miss that point wins by a margin worth 0.9-0.98 raw
(0.99+ once calibrated). So such labels came out sure where they were mostly wrong:

- under the hard preset (``configs/scenarios/hard.toml``, lp-l1, 400 frames): 94 of 96
  lone labels over CMU 85_02 seeds 1-2, 135_02 seed 0 and 03_rolling seed 0 were wrong (a
  ghost taken 20-200 mm from the marker's true place), 15 of them reported sure;
- on the accuracy matrix's default scenario (seed 0, 600 frames): 26 of 44 over CMU 85_02,
  03_rolling and the tennis serve, and 41 of 52 on the racing take with deletions;
- on real takes relabeled by ``track`` (``bench/real_takes.py``'s starts) they are right
  more often, as a real marker does flicker into view for a frame: where the file labels the
  marker, 151 of 173 on the basket sprint and 20 of 20 on the racing take (none on 03_rolling,
  the tennis serve or CMU 135_02), 89 %; 44 more (42 on the basket sprint, 2 on 03_rolling)
  took a point the file names for no marker.

Frames outside the take count as unlabeled; the first frame, which the user labeled, is
never lone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def lone_labels(labeled: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``(F, N)`` the labels of ``labeled`` ``(F, N)`` with no label in the frame before nor after
    (module doc); frame 0 never."""
    before = np.zeros_like(labeled)
    after = np.zeros_like(labeled)
    before[1:], after[:-1] = labeled[:-1], labeled[1:]
    lone: NDArray[np.bool_] = labeled & ~before & ~after
    lone[:1] = False
    return lone
