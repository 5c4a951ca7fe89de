"""The input points no marker took, kept as unlabeled trajectories: nothing the input
carried is lost from the output.

A mocap system writes what it could not name as unlabeled trajectories (``*0``, ``*1``, ...
in Vicon's C3D files) for the user to name by hand. markerflow does the same with the points
its labeling left over (ghosts, and markers it lost and did not re-acquire): they are chained
frame to frame into fragments, each point joined to the nearest leftover point of the frame
before within ``reach`` (a gated assignment, so two fragments never share a point), and the
fragments packed into as few channels as possible, a channel holding fragments one after
another with at least one empty frame between them, so each fragment's ends show. (One
channel per fragment, as Vicon writes them, would make thousands of channels of a take with
ghosts; a gap filler run over a packed channel would join its fragments, so fill markers,
not ``*N``.)
"""

from __future__ import annotations

import heapq
from dataclasses import replace

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from service.io.recording import LabeledTrajectories

MIN_REACH_MM = 10.0  # below this, noise alone splits a still point's fragment
REACH_PER_STEP = 2.0  # times the 99th percentile of the labeled markers' steps


def with_leftover_points(result: LabeledTrajectories, points: list[np.ndarray] | None) -> LabeledTrajectories:
    """``result`` with the points of ``points`` (the capture's, one array per frame) that no
    marker took as its ``unlabeled`` channels; unchanged without 3D points or point identities."""
    if points is None or result.point_index.size == 0:
        return result
    leftover = leftover_points(points, result.point_index)
    return replace(result, unlabeled=unlabeled_channels(leftover, reach_from_labels(result.positions)))


def leftover_summary(result: LabeledTrajectories) -> dict[str, int | list[str]]:
    """``unlabeled_points``: input samples no marker took; ``unlabeled_trajectories``: the
    channels (``*N`` in a C3D output) that hold them; ``unlabeled_copies``: the markers whose
    point one of them repeats (``copied_markers``)."""
    present = np.isfinite(result.unlabeled).all(axis=2)
    return {"unlabeled_points": int(present.sum()), "unlabeled_trajectories": int(present.shape[1]),
            "unlabeled_copies": copied_markers(result)}


def copied_markers(result: LabeledTrajectories) -> list[str]:
    """Markers whose point an unlabeled channel repeats in every frame it has one: a column
    the input carried twice (HDM05's ``*0``-``*2``), kept as a channel beside the label."""
    present = np.isfinite(result.unlabeled).all(axis=2)
    copied: list[str] = []
    for channel in np.flatnonzero(present.any(axis=0)):
        frames = present[:, channel]
        same = (result.positions[frames] == result.unlabeled[frames, channel][:, None, :]).all(axis=2).all(axis=0)
        copied += [result.names[int(marker)] for marker in np.flatnonzero(same)[:1]]
    return copied


def leftover_note(summary: dict, kept: bool = True) -> str:
    """The summary line's mention of them (``summary`` holds ``leftover_summary``'s keys),
    empty when there are none; ``kept`` False for an output that holds labels only (TRC, CSV),
    which says so instead."""
    points, trajectories, copies = summary["unlabeled_points"], summary["unlabeled_trajectories"], summary["unlabeled_copies"]
    if not points:
        return ""
    if not kept:
        return f"; {points} points no marker took are not in this table (a .c3d output keeps them as *N)"
    plural = "trajectory" if trajectories == 1 else "trajectories"
    repeat = f" ({len(copies)} repeating a marker's point: {', '.join(copies)})" if copies else ""
    return f"; {points} points no marker took kept as {trajectories} unlabeled {plural} *N{repeat}"


def leftover_points(points: list[np.ndarray], point_index: np.ndarray) -> list[np.ndarray]:
    """Per frame, the ``(L, 3)`` points of ``points[f]`` that no marker took (``point_index[f]``, -1 none)."""
    leftover = []
    for f, cloud in enumerate(points):
        free = np.ones(len(cloud), bool)
        taken = point_index[f][point_index[f] >= 0] if f < len(point_index) else np.zeros(0, int)
        free[taken] = False
        leftover.append(np.asarray(cloud, float).reshape(-1, 3)[free])
    return leftover


def reach_from_labels(positions: np.ndarray) -> float:
    """How far (mm) a leftover point may move between frames and stay one fragment: twice the
    99th percentile of the labeled markers' frame-to-frame steps (``(frames, markers, 3)``),
    so it follows the take's own motion and frame rate; ``MIN_REACH_MM`` at least."""
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=2)
    steps = steps[np.isfinite(steps)]
    return max(MIN_REACH_MM, REACH_PER_STEP * float(np.percentile(steps, 99))) if steps.size else 5 * MIN_REACH_MM


def unlabeled_channels(leftover: list[np.ndarray], reach: float) -> np.ndarray:
    """``(frames, channels, 3)``: the leftover points chained into fragments and packed into
    channels (module doc), NaN where a channel holds nothing."""
    starts, fragments = _fragments(leftover, reach)
    channel_of, n_channels = _packed(starts, [len(points) for points in fragments])
    out = np.full((len(leftover), n_channels, 3), np.nan)
    for start, points, channel in zip(starts, fragments, channel_of):
        out[start : start + len(points), channel] = points
    return out


def _fragments(leftover: list[np.ndarray], reach: float) -> tuple[list[int], list[list[np.ndarray]]]:
    """Each fragment's first frame and its points, frame by frame."""
    starts: list[int] = []
    fragments: list[list[np.ndarray]] = []
    active: list[int] = []  # fragments with a point in the frame before
    for f, points in enumerate(leftover):
        continued = np.zeros(len(points), bool)
        following: list[int] = []
        if active and len(points):
            distance = cdist(np.array([fragments[i][-1] for i in active]), points)
            rows, cols = linear_sum_assignment(np.where(distance <= reach, distance, 1e12))
            for r, c in zip(rows, cols):
                if distance[r, c] <= reach:
                    fragments[active[r]].append(points[c])
                    continued[c] = True
                    following.append(active[r])
        for c in np.flatnonzero(~continued):
            starts.append(f)
            fragments.append([points[c]])
            following.append(len(fragments) - 1)
        active = following
    return starts, fragments


def _packed(starts: list[int], lengths: list[int]) -> tuple[list[int], int]:
    """The channel of each fragment and the channel count: interval partitioning by first
    frame, a channel reused once its last fragment ended two or more frames before."""
    channel_of = [0] * len(starts)
    free: list[tuple[int, int]] = []  # (first frame the channel can take, channel)
    n_channels = 0
    for i in sorted(range(len(starts)), key=starts.__getitem__):
        if free and free[0][0] <= starts[i]:
            _, channel = heapq.heappop(free)
        else:
            channel, n_channels = n_channels, n_channels + 1
        channel_of[i] = channel
        heapq.heappush(free, (starts[i] + lengths[i] + 1, channel))
    return channel_of, n_channels
