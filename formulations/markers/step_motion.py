"""The expected displacement of each window step: a running median of the guide's own steps.

The window's step cost compares a path's step r_j - r_i with the displacement delta_n(m)
expected into frame m (``window.costs``). The guide track's delta is the difference of its
own last two picks, so one wrong pick (a ghost nearer the prediction than the marker's own
point, or a burst of noise) sets a wrong delta for the two steps after it, and the true path
pays a burst cost there while a neighbour's occluded path, with a delta from its own
neighbours, does not: the occluded marker takes the point.

Where the guide saw the marker before frame m and in the frames around it, the expected step
is instead the centred median, per axis, of the guide's steps over frames m - h .. m + h:

    delta_n(m) = median{ v_n(k) : |k - m| <= h, the guide saw n before frame k },

but only for a marker whose steps in the window differ from one another mostly by noise. From
the guide's picks x: the robust scale s_2 of the marker's second differences D^2 x (its three
axes pooled; one step's change, 6 sigma^2 + q_n^2 with q_n its acceleration) and the
window's noise sigma from the third differences of every marker (20 sigma^2 under noise
alone; ``noise``). The median is used where s_2^2 < 2 * 6 sigma^2, i.e. q_n^2 < 6 sigma^2:
there it removes more noise than it smooths away motion. A hand pushing a racing wheelchair's rim at 70 Hz accelerates
far more than its noise, and its last step is kept (smoothing it there exchanged two glove
markers 30 mm apart: the real take 97.21 -> 89.75 %). Steps after a gap keep the
displacement the neighbours imply (``MarkerState``). Seed-0 accuracy matrix (85 rows): lp-l1
96.648 -> 97.003 %, swaps 2,203 -> 1,726; seeds 1-2 (80 rows) 98.768 -> 98.739 %, 608 -> 549.
h = 1 and h = 3 (with the median for every marker) gave 96.710 and 97.020 % on seed 0, the
latter 98.502 % on seeds 1-2.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.guide import GuideTrack
from formulations.markers.noise import MAD_TO_SIGMA

HALF_WIDTH = 2  # h: frames each side; one wrong pick in 2h + 1 = 5 steps leaves the median
MIN_MARKER_SAMPLES = 6  # second differences (frames x axes) a marker needs in the window to be judged
MIN_NOISE_SAMPLES = 10  # third differences the window needs for its noise


def expected_steps(guide: GuideTrack, half_width: int = HALF_WIDTH) -> np.ndarray:
    """``(M, N, 3)`` delta per window frame and marker (module doc); NaN where unknown."""
    velocity = guide.velocity
    seen = (guide.unseen == 0) & np.isfinite(velocity).all(axis=2)
    frames = len(velocity)
    if frames == 0 or half_width == 0:
        return velocity
    steps = np.where(seen[..., None], velocity, np.nan)
    padded = np.pad(steps, ((half_width, half_width), (0, 0), (0, 0)), constant_values=np.nan)
    median = masked_median(np.stack([padded[k : k + frames] for k in range(2 * half_width + 1)]))
    smoothed = seen[..., None] & np.isfinite(median) & noise_dominated(guide, seen)[None, :, None]
    expected: np.ndarray = np.where(smoothed, median, velocity)
    return expected


def noise_dominated(guide: GuideTrack, seen: np.ndarray) -> np.ndarray:
    """``(N,)`` markers whose steps vary mostly by noise in this window (module doc)."""
    picked = np.zeros_like(seen)
    picked[:-1] = seen[1:]  # the guide saw n in frame f when it steps from there into f + 1
    position = np.full_like(guide.velocity, np.nan)
    position[:-1] = guide.predicted[1:] - guide.velocity[1:]
    position[~picked] = np.nan
    markers = seen.shape[1]
    second = np.abs(np.diff(position, n=2, axis=0)).transpose(0, 2, 1).reshape(-1, markers)
    third = np.abs(np.diff(position, n=3, axis=0))
    third = third[np.isfinite(third)]
    if third.size < MIN_NOISE_SAMPLES:
        return np.zeros(markers, dtype=bool)
    noise_var = (MAD_TO_SIGMA * np.median(third)) ** 2 / 20.0
    enough = np.isfinite(second).sum(axis=0) >= MIN_MARKER_SAMPLES
    change_var = (MAD_TO_SIGMA * masked_median(second)) ** 2
    dominated: np.ndarray = enough & (change_var < 2 * 6 * noise_var)
    return dominated


def masked_median(values: np.ndarray) -> np.ndarray:
    """Median over axis 0 of the finite entries (NaN where none): ``np.nanmedian`` without
    its warning on all-NaN slices, which are expected here (a marker unseen in a stretch)."""
    ordered = np.sort(values, axis=0)  # NaN last
    count = np.isfinite(ordered).sum(axis=0)
    low = np.take_along_axis(ordered, (np.maximum(count - 1, 0) // 2)[None], axis=0)[0]
    high = np.take_along_axis(ordered, (count // 2)[None], axis=0)[0]
    median: np.ndarray = np.where(count > 0, 0.5 * (low + high), np.nan)
    return median
