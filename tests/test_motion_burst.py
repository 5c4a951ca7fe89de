"""A limb that bursts into motion after a still stretch (issue 14: fast motion).

A serve at 50 Hz: the arm rests for three seconds, so every marker's learned motion
residual falls to the noise; then it swings 150 degrees in 14 frames, the hand moving up
to 220 mm a frame and accelerating by up to 60 mm a frame^2. The slow envelope of the
motion residual cannot rise that fast (it is clipped and learned at 2 % a frame, so one
mislabeled frame cannot open every later gate); the fast estimate of the last frames
(``motion.learn_burst``) does, and widens the gates and step costs while the burst lasts.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import formulations.markers.state as marker_state
from formulations.markers.motion import learn_burst, learn_motion
from service import Capture, CaptureLabeling

RATE, STILL, SWING, FRAMES = 50.0, 150, 14, 194
SHOULDER = np.array([0.0, 0.0, 1400.0])
# Upper arm, wrist pair and hand in the shoulder's frame (mm): elbow, two wrist, finger, hand.
ARM = np.array([[0, 300, 0], [30, 560, 20], [-30, 560, 20], [0, 640, 0], [40, 620, -30]], float)
TRUNK = np.array([[0, -150, 0], [0, 150, 0], [0, 0, -300], [100, 0, -300], [-100, 0, -300], [0, 0, -600]], float)


def _serve() -> np.ndarray:
    """``(frames, markers, 3)``: still, then a 150-degree swing about the shoulder with a smooth start and stop."""
    s = np.clip((np.arange(FRAMES) - STILL) / SWING, 0.0, 1.0)
    angle = np.radians(150.0) * (6 * s**5 - 15 * s**4 + 10 * s**3)
    swing = Rotation.from_rotvec(np.outer(angle, [1.0, 0.0, 0.0])).as_matrix()
    arm = np.einsum("fij,kj->fki", swing, ARM) + SHOULDER
    return np.concatenate([arm, np.broadcast_to(TRUNK + SHOULDER, (FRAMES,) + TRUNK.shape)], axis=1)


def _mislabeled_frames() -> list[int]:
    truth = _serve()
    noisy = truth + np.random.default_rng(0).normal(0.0, 0.5, truth.shape)
    names = [f"m{i}" for i in range(truth.shape[1])]
    labels, _ = CaptureLabeling(Capture(names, noisy[0], RATE, points=list(noisy))).label()
    own = np.arange(truth.shape[1])
    return [f for f in range(FRAMES) if (labels.point_index[f] != own).any()]


def test_the_serve_is_fast_enough_to_matter():
    step = np.linalg.norm(np.diff(_serve(), axis=0), axis=2)
    assert step.max() > 200.0
    assert np.linalg.norm(np.diff(_serve(), n=2, axis=0), axis=2).max() > 50.0


def test_every_marker_keeps_its_point_through_the_burst():
    wrong = _mislabeled_frames()
    assert not wrong, f"{len(wrong)} frames mislabeled from frame {wrong[0]}"


def test_without_the_burst_estimate_the_hand_is_dropped(monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setattr(marker_state, "learn_burst", lambda var, *_: np.zeros_like(var))
    wrong = _mislabeled_frames()
    assert len(wrong) > 10 and wrong[0] > STILL


def _learned(residuals: np.ndarray, var: float = 100.0, samples: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Slow envelope and burst of one marker after each of ``residuals`` ``(frames, 3)``,
    fed as ``MarkerState.advance`` feeds them: ``(frames,)`` each."""
    envelope, count, burst, last = np.array([var]), np.array([samples]), np.array([0.0]), np.zeros((1, 3))
    usable = np.array([True])
    envelopes, bursts = [], []
    for residual in residuals[:, None]:
        step_var = np.maximum(envelope, burst)
        envelope, count = learn_motion(envelope, count, residual, usable)
        burst, last = learn_burst(burst, residual, last, usable, step_var), residual
        envelopes.append(envelope[0])
        bursts.append(burst[0])
    return np.array(envelopes), np.array(bursts)


def _still_residuals(frames: int, sd: float, seed: int) -> np.ndarray:
    """Constant-velocity residuals of a still marker under ``sd`` mm of noise per axis."""
    x = np.random.default_rng(seed).normal(0.0, sd, (frames + 2, 3))
    residual: np.ndarray = x[2:] - 2 * x[1:-1] + x[:-2]
    return residual


@pytest.mark.parametrize("seed", range(3))
def test_noise_alone_raises_no_burst(seed: int):
    """Noise residuals alternate, so the burst stays under the learned envelope: a fast mean
    of squares would exceed it on a sixth to a third of the frames and widen every gate of a
    noisy take."""
    envelope, burst = _learned(_still_residuals(400, 4.0, seed))
    squares = (_still_residuals(400, 4.0, seed) ** 2).mean(axis=1)
    fast_squares = np.array([0.5 ** np.arange(k + 1)[::-1] @ squares[: k + 1] * 0.5 for k in range(400)])
    assert (burst[100:] > envelope[100:]).mean() < 0.02
    assert (fast_squares[100:] > envelope[100:]).mean() > 0.15


def test_burst_variance_follows_a_growing_acceleration_while_the_envelope_lags():
    """Residuals doubling each frame from 2 mm (a limb speeding up) are followed within a
    factor of two in sd; the slow envelope has barely moved; calm returns within frames."""
    noise = _still_residuals(200, 0.4, 1)
    ramp = np.repeat(2.0 * 2.0 ** np.arange(6), 3).reshape(6, 3)  # 2 ... 64 mm per axis
    envelope, burst = _learned(np.concatenate([noise, ramp, np.zeros((6, 3))]))
    assert envelope[199] < 3.0 and burst[199] < 5.0
    assert np.sqrt(burst[205]) > 32.0  # the last residual was 64 mm per axis
    assert envelope[205] < 0.1 * 64.0**2
    assert burst[-1] < 0.02 * 64.0**2


def test_an_unseen_marker_forgets_its_burst():
    sixty = np.full((1, 3), 60.0)
    assert learn_burst(np.array([900.0]), sixty, sixty, np.array([False]), np.array([900.0]))[0] == 0.0


def test_one_spike_widens_the_next_gate_only_a_little():
    """A single 60 mm residual (a wrong point, a glitch) on a marker learned on 1 mm noise."""
    spike = np.zeros((1, 3)) + 60.0
    _, burst = _learned(np.concatenate([_still_residuals(200, 0.4, 2), spike]))
    assert np.sqrt(burst[-1]) < 0.1 * 60.0
