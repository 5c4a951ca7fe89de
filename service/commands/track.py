"""``markerflow track``: relabel a recording from its labeled first frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from service.cloud_labeler import CloudLabeler
from service.commands.report import out, window_progress
from service.formats import check_output, read_labeled, write_labeled
from service.formulation_spec import formulation_from_spec
from service.recording import Recording, UnlabeledCloud


def run_track(input: Path, output: Path, formulation: str, window: int, shuffle: bool) -> None:
    """Treat every frame of ``input`` as unlabeled points, label them, write ``output``."""
    check_output(output)
    recording = read_labeled(input)
    cloud = unlabeled_cloud(recording, shuffle)
    labeler = CloudLabeler(formulation=formulation_from_spec(formulation), window=window)
    with window_progress(f"labeling {input.name}") as progress:
        result, windows = labeler.label(cloud, recording.names, recording.positions[0], progress)
    write_labeled(output, result)
    integral = np.mean([w.integral for w in windows]) if windows else 1.0
    out.print(
        f"{input.name}: {recording.n_markers} markers x {recording.n_frames} frames -> {output} "
        f"({result.occluded.mean():.1%} occluded, {integral:.0%} windows integral, "
        f"max gap {max((w.gap for w in windows), default=0.0):.1e})"
    )


def unlabeled_cloud(recording: Recording, shuffle: bool, seed: int = 0) -> UnlabeledCloud:
    """The points of each frame without their labels (missing samples dropped)."""
    rng = np.random.default_rng(seed)
    present = ~recording.missing()
    frames = []
    for f in range(recording.n_frames):
        points = recording.positions[f][present[f]]
        frames.append(points[rng.permutation(len(points))] if shuffle else points)
    return UnlabeledCloud(points=frames, rate=recording.rate)
