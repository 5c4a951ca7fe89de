"""The built-in demo scene: a walking figure wearing a Plug-in-Gait-style marker set.

The figure is the kinematic tree of :mod:`service.evaluation.scene_markers`. Each joint angle is
a sinusoid of the gait phase, the pelvis travels forward with a sway and a bob, and
each marker is a fixed offset in its segment's frame. A seed varies the gait
frequency, the swing amplitudes and phases, and the marker placement, so that
different seeds behave like different takes of different people.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from service.errors import InputError
from service.evaluation.scene_markers import MARKERS, SEGMENTS, mirror_name
from service.io.recording import Recording

_PELVIS_HEIGHT = 975.0  # mm; legs and feet in scene_markers reach the floor from here
_STRIDE = 1250.0  # mm per gait cycle; about 1.2 m/s at the chosen cadence
_SWAY, _BOB = 20.0, 15.0  # mm; the pelvis shifts over the stance leg and rises mid-stance


class _Swing(NamedTuple):
    """A joint angle ``bias + amp * sin(harmonic * gait + 2 pi phase)``, in degrees.

    Axis 0 rolls about x (distal end to the left), 1 pitches about y (distal end
    backward: hip extension, knee flexion) and 2 yaws about z (turning left).
    """

    segment: str
    axis: int
    bias: float
    amp: float
    phase: float
    harmonic: float = 1.0


# Trunk and left side only: the right limbs replay the left half a stride later.
_SWINGS = (
    _Swing("pelvis", 0, 0.0, 4.0, 0.5),  # the swing side drops
    _Swing("pelvis", 2, 0.0, 5.0, 0.5),  # the swinging leg's hip leads
    _Swing("pelvis", 1, 4.0, 2.0, 0.0, 2.0),
    _Swing("thorax", 2, 0.0, 7.0, 0.0),  # the trunk counter-rotates
    _Swing("thorax", 1, 3.0, 1.5, 0.25, 2.0),
    _Swing("head", 1, -3.0, 3.0, 0.0, 2.0),
    _Swing("Lthigh", 1, -8.0, 24.0, 0.5),
    _Swing("Lshank", 1, 30.0, 28.0, 0.25),  # the knee bends most while the hip flexes
    _Swing("Lfoot", 1, 0.0, 10.0, 0.0),
    _Swing("Lupperarm", 1, 0.0, 20.0, 0.0),  # arms swing against the legs
    _Swing("Lupperarm", 0, 8.0, 3.0, 0.0, 2.0),  # abducted so hands clear the hips
    _Swing("Lupperarm", 0, 0.0, 15.0, 0.0, 0.25),  # a slow dance-like arm raise
    _Swing("Lforearm", 1, -25.0, 15.0, 0.0),
    _Swing("Lhand", 1, 0.0, 8.0, 0.25),
)


def generate_scene(n_frames: int = 600, rate: float = 120.0, seed: int = 0) -> Recording:
    """Synthesise a labeled walking figure, so the demo needs no external data.

    Args:
        n_frames: Number of frames to generate.
        rate: Frames per second.
        seed: Seed for the gait and marker-placement variation; equal seeds give
            identical scenes.

    Returns:
        A recording of 39 markers in millimetres, z up, walking along +x, with no gaps.

    Raises:
        InputError: If ``n_frames`` is below one or ``rate`` is not positive.
    """
    if n_frames < 1:
        raise InputError(f"the demo scene needs at least one frame, got {n_frames}")
    if not rate > 0:
        raise InputError(f"frame rate must be positive, got {rate}")
    rng = np.random.default_rng(seed)
    cadence = rng.uniform(0.9, 1.05)  # gait cycles per second
    gait = 2.0 * np.pi * cadence * np.arange(n_frames) / rate
    local = _local_rotations(gait, rng)
    pose = _forward_kinematics(_pelvis_path(gait), local)
    positions = _place_markers(pose, rng)
    return Recording(names=[m.name for m in MARKERS], positions=positions, rate=rate)


def _pelvis_path(gait: np.ndarray) -> np.ndarray:
    """``(frames, 3)`` pelvis origin: forward one stride per cycle, swaying and bobbing."""
    forward = _STRIDE * gait / (2.0 * np.pi)
    height = _PELVIS_HEIGHT + _BOB * np.cos(2.0 * gait)
    return np.stack([forward, -_SWAY * np.sin(gait), height], axis=1)


def _local_rotations(gait: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """``(frames, 3, 3)`` rotation of every segment relative to its parent."""
    angles = {s.name: np.zeros((len(gait), 3)) for s in SEGMENTS}
    scales = rng.uniform(0.8, 1.2, len(_SWINGS))
    shifts = rng.normal(0.0, 0.02, len(_SWINGS))
    for swing, scale, shift in zip(_SWINGS, scales, shifts):
        for name, lag, sign in _sides(swing.segment, swing.axis):
            wave = np.sin(swing.harmonic * (gait - lag) + 2.0 * np.pi * (swing.phase + shift))
            angles[name][:, swing.axis] += sign * (swing.bias + scale * swing.amp * wave)
    return {name: _rotation(np.radians(a)) for name, a in angles.items()}


def _sides(segment: str, axis: int) -> list[tuple[str, float, float]]:
    """The segments a left-side swing drives: ``(name, phase lag, sign)``."""
    if not segment.startswith("L"):
        return [(segment, 0.0, 1.0)]
    # Mirroring in the sagittal plane flips roll and yaw but keeps pitch.
    return [(segment, 0.0, 1.0), (mirror_name(segment), np.pi, 1.0 if axis == 1 else -1.0)]


def _rotation(angles: np.ndarray) -> np.ndarray:
    """``(frames, 3, 3)`` from x/y/z angles in radians, applied pitch, then roll, then yaw."""
    yaw, roll, pitch = (_axis_rotation(axis, angles[:, axis]) for axis in (2, 0, 1))
    return yaw @ roll @ pitch


def _axis_rotation(axis: int, theta: np.ndarray) -> np.ndarray:
    """``(frames, 3, 3)`` right-handed rotations by ``theta`` about one coordinate axis."""
    i, j = ((1, 2), (2, 0), (0, 1))[axis]
    c, s = np.cos(theta), np.sin(theta)
    r = np.zeros((len(theta), 3, 3))
    r[:, axis, axis] = 1.0
    r[:, i, i], r[:, j, j], r[:, i, j], r[:, j, i] = c, c, -s, s
    return r


def _forward_kinematics(
    root: np.ndarray, local: dict[str, np.ndarray]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """World ``(rotation, origin)`` of every segment; SEGMENTS lists parents first."""
    pose: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for seg in SEGMENTS:
        if seg.parent is None:
            pose[seg.name] = (local[seg.name], root)
            continue
        rot, origin = pose[seg.parent]
        pose[seg.name] = (rot @ local[seg.name], origin + rot @ np.asarray(seg.joint))
    return pose


def _place_markers(
    pose: dict[str, tuple[np.ndarray, np.ndarray]], rng: np.random.Generator
) -> np.ndarray:
    """``(frames, markers, 3)``; each seed places the markers a few mm differently."""
    placement = rng.normal(0.0, 3.0, (len(MARKERS), 3))
    columns = []
    for marker, error in zip(MARKERS, placement):
        rot, origin = pose[marker.segment]
        columns.append(origin + rot @ (np.asarray(marker.offset) + error))
    return np.stack(columns, axis=1)
