"""Camera jobs, per camera: the detections there were, and those the labels account for."""

from __future__ import annotations

from collections import Counter

import numpy as np

from service.capture.capture import Capture
from service.web.job_data import Labels
from service.web.plots.figure import new_figure, svg_bytes

USED_PX = 3.0  # a detection within this many pixels of a labeled marker's projection was used


def detections_used(capture: Capture, labels: Labels) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per camera, ``(detections, used)`` per frame: how many 2D detections it had, and how
    many lie within ``USED_PX`` of a seen labeled marker projected into it. The result keeps
    no detection identities, so use is recovered by reprojection."""
    cameras, frames = capture.camera_frames()
    n_frames = min(len(frames), labels.occluded.shape[0])
    seen = np.where(labels.occluded[:n_frames, :, None], np.nan, labels.positions[:n_frames])
    counts = {}
    for c, camera in enumerate(cameras):
        projected = camera.project(np.nan_to_num(seen.reshape(-1, 3))).reshape(n_frames, -1, 2)
        projected[labels.occluded[:n_frames]] = np.nan
        total, used = np.zeros(n_frames, dtype=int), np.zeros(n_frames, dtype=int)
        for f in range(n_frames):
            detections = frames[f][c]
            total[f] = len(detections)
            if len(detections):
                gaps = np.linalg.norm(detections[:, None, :] - projected[f][None, :, :], axis=2)
                used[f] = int((np.nan_to_num(gaps, nan=np.inf).min(axis=1, initial=np.inf) <= USED_PX).sum())
        counts[camera.name] = (total, used)
    return counts


def cameras_svg(counts: dict[str, tuple[np.ndarray, np.ndarray]]) -> bytes:
    """One panel per camera: detections per frame (solid) and used ones (dashed)."""
    figure = new_figure(9.0, 0.8 + 1.4 * len(counts))
    panels = np.atleast_1d(figure.subplots(len(counts), 1, sharex=True))
    for axes, (name, (total, used)) in zip(panels, counts.items()):
        frames = np.arange(len(total))
        axes.step(frames, total, "-", where="mid", color="0.1", linewidth=1.0, label="detections")
        axes.step(frames, used, "--", where="mid", color="#5d3a9b", linewidth=1.2,
                  label=f"used (within {USED_PX:g} px of a label)")
        axes.set_ylabel(name, fontsize=8)
        axes.grid(alpha=0.3)
    panels[0].legend(loc="upper right", fontsize=7, ncols=2)
    panels[-1].set_xlabel("frame")
    title = "detections per camera and frame"
    figure.suptitle(title, fontsize=10)
    return svg_bytes(figure, title)


def best_views(labels: Labels) -> list[tuple[str, str, float, int]]:
    """Per marker with a best view: the camera chosen most often, its share of the frames that
    name one, and how often the choice switches."""
    if labels.best_view is None:
        return []
    rows = []
    for m, name in enumerate(labels.names):
        choices = [frame[m] for frame in labels.best_view if frame[m] is not None]
        if choices:
            camera, times = Counter(choices).most_common(1)[0]
            switches = sum(a != b for a, b in zip(choices, choices[1:]))
            rows.append((name, str(camera), times / len(choices), switches))
    return rows
