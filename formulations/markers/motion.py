"""What a take's labels teach about its markers' motion: residual and drift variances.

Two running estimates feed the likelihood costs (``markers.likelihood``) and the gates:

* the motion residual of a marker seen in three frames in a row,
  e = x_t - (x_(t-1) + v), v = x_(t-1) - x_(t-2), of per-axis variance 6 sigma^2 + q_n^2
  (``noise.TakeNoise``: the take's noise sigma and the marker's own acceleration q_n);
* the drift of an occluded marker's prediction: reappearing h = unseen + 1 frames after
  its last sighting at distance e from where it was predicted, it gives one sample of
  (|e|^2 / 3 - motion_var) / (h - 1), the variance added per frame unseen.

Each is a running mean of squares learned at rate 1 / (samples + 2) down to
``MOTION_RATE``: the first samples replace the prior, later ones follow slow change; the
motion residual's falls ``MOTION_DECAY`` times slower than it rises, and never below
``MOTION_VAR_FLOOR_MM2``.
Each square is first limited to ``MOTION_CLIP`` times the current value, so a mislabeled
frame cannot open every later gate.

A third, fast estimate follows a burst: the running mean, at rate ``BURST_RATE`` either
way, of the lag product e_t . e_(t-1) / 3 of consecutive motion residuals, floored at 0 and
limited to ``MOTION_CLIP`` times the variance the step was predicted with. A serve's wrist
goes from still to 100 mm per frame^2 within ten frames, long before the slow estimate (at
rate ``MOTION_RATE``) has risen. While a limb accelerates its residuals persist and the
product is about the next residual's square; noise alone gives residuals that alternate
(e_t = n_t - 2 n_(t-1) + n_(t-2) has lag-one correlation -2/3), a negative product, and
no burst: a fast mean of plain squares would follow the noise and widen every gate of a
noisy take. It falls as fast once the limb is calm.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.means import axis_mean

# Before a marker's own motion is known its residual is taken as 10 mm per axis: wide
# enough for one frame of a fast limb at 50 Hz, learned away within a few frames.
MOTION_VAR_PRIOR_MM2 = 100.0
# Prior drift, (2.5 mm)^2 per frame unseen: the old fixed prediction sd grew 2.5 mm a frame.
DRIFT_VAR_PRIOR_MM2 = 6.25
MOTION_RATE = 0.02  # weight of one new sample once learned: about the last 50
# A calm stretch lowers the variance ten times slower than motion raises it: a limb that
# accelerated a few hundred frames ago may do so again (real motion comes in bursts).
MOTION_DECAY = 0.1
# (0.5 mm)^2: below the centroid noise of optical systems; filtered takes go lower.
MOTION_VAR_FLOOR_MM2 = 0.25
MOTION_CLIP = 9.0  # a sample counts at most as a 3-sigma one
BURST_RATE = 0.5  # the fast estimate: half the last frame, half what it said before


def learn_motion(
    var: np.ndarray, samples: np.ndarray, residual: np.ndarray, usable: np.ndarray, decay: float = MOTION_DECAY,
) -> tuple[np.ndarray, np.ndarray]:
    """``motion_var`` and its sample count after one frame (module doc).

    With ``decay`` = 1 this is the running mean of squares, the variance itself; below 1 it
    is an envelope above it, what the costs need of a motion that comes in bursts.

    Args:
        var, samples: ``(N,)`` current estimate and count.
        residual: ``(N, 3)`` observed minus constant-velocity prediction.
        usable: ``(N,)`` markers seen now and in the two frames before.
        decay: Rate of a lowering step relative to a raising one.
    """
    square = np.minimum(axis_mean(residual**2), MOTION_CLIP * var)
    rate = np.maximum(1.0 / (samples + 2), np.where(square > var, MOTION_RATE, MOTION_RATE * decay))
    learned = np.maximum(var + rate * (square - var), MOTION_VAR_FLOOR_MM2)
    return np.where(usable, learned, var), samples + usable


def learn_drift(
    var: np.ndarray, samples: np.ndarray, residual: np.ndarray, reappearing: np.ndarray,
    unseen: np.ndarray, motion_var: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``drift_var`` (one value for all markers) and its count after one frame (module doc).

    Args:
        residual: ``(N, 3)`` observed minus predicted position.
        reappearing: ``(N,)`` markers seen now after ``unseen`` >= 1 frames unseen.
    """
    usable = reappearing & (unseen >= 1)
    if not usable.any():
        return var, samples
    per_frame = np.maximum(axis_mean(residual[usable] ** 2) - motion_var[usable], 0.0) / unseen[usable]
    current, count = float(var[0]), int(samples[0])
    for sample in np.minimum(per_frame, MOTION_CLIP * current):
        current += max(1.0 / (count + 2), MOTION_RATE) * (sample - current)
        count += 1
    return np.full_like(var, current), np.full_like(samples, count)


def learn_burst(
    var: np.ndarray, residual: np.ndarray, last_residual: np.ndarray, usable: np.ndarray, step_var: np.ndarray,
) -> np.ndarray:
    """``burst_var`` after one frame: the fast running mean of lag products (module doc).

    Args:
        var: ``(N,)`` current estimate.
        residual, last_residual: ``(N, 3)`` observed minus constant-velocity prediction, this
            frame and the last (0 where that one was not usable).
        usable: ``(N,)`` markers seen now and in the two frames before; the others forget
            their burst (a reappearing marker's residual is its drift, not its motion).
        step_var: ``(N,)`` the variance the step was predicted with: a product counts at
            most ``MOTION_CLIP`` times it, so one wrong point widens the next frame's gate a
            little, while an acceleration that grows over frames (a serve's, about doubling
            each frame) is followed.
    """
    sample = np.minimum(np.maximum(axis_mean(residual * last_residual), 0.0), MOTION_CLIP * step_var)
    learned: np.ndarray = np.where(usable, var + BURST_RATE * (sample - var), 0.0)
    return learned
