"""The input's markers a subject model lacks, carried into the output as the input had them.

Labeling from a model names the model's markers only. A .c3d copy of the input keeps its
other points untouched (``write_c3d``); a TRC or CSV table, or a new C3D (the input lacks a
model marker), would drop them: they are appended here as their own columns, the input's
samples under the input's names, so the output still holds everything the input did.

Their samples are taken out of the capture before labeling (``out_of``): they keep the
input's names, so a model marker that took one wrote one point under two names (BTS from
frame 337 with a model of its first 337 frames: SCR2 on "r bar 2"'s point in 170 frames),
and one no marker took came out again as a leftover ``*N`` trajectory. So each sample is
written once, and the summary's count of leftover points is of points nowhere else.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from service.capture.capture import Capture
from service.io.recording import LabeledTrajectories, Recording, is_unlabeled
from service.labeling.absent_markers import with_absent

SAME_SAMPLE_MM = 1e-6  # a capture point is the input's sample copied, not recomputed: exact up to round-off


@dataclass(frozen=True)
class CarriedMarkers:
    """The input's named markers a model lacks over the labeled span.

    Attributes:
        names: Their input names (the input's own ``*N`` trajectories are not among them: a
            relabel replaces those).
        positions: ``(frames, markers, 3)`` mm, the span's input samples, NaN where missing.
    """

    names: list[str]
    positions: np.ndarray

    @classmethod
    def of(cls, recording: Recording, labeled: list[str], start: int, frames: int) -> CarriedMarkers:
        """The markers of ``recording`` not in ``labeled``, input frames ``start .. start + frames - 1``."""
        named = set(labeled)
        columns = [i for i, name in enumerate(recording.names) if name not in named and not is_unlabeled(name)]
        return cls([recording.names[i] for i in columns], recording.positions[start : start + frames, columns])

    def out_of(self, capture: Capture) -> Capture:
        """``capture`` (3D points, frames of this span) without these markers' samples, one
        point per sample: an exact copy of a sample under another name stays."""
        if capture.points is None or not self.names:
            return capture
        return replace(capture, points=[_without(frame, self.positions[f]) for f, frame in enumerate(capture.points)])

    def appended_to(self, result: LabeledTrajectories) -> LabeledTrajectories:
        """``result`` with these markers as further columns, occluded where missing: for an
        output that is not a copy of the input C3D (which keeps them itself)."""
        return with_absent(result, self.names, self.positions)


def _without(points: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """``points`` less the one nearest each finite sample, where it is that sample (the first
    of exact copies: a model marker's sample copied under another name keeps its point)."""
    samples = samples[np.isfinite(samples).all(axis=1)]
    if not len(samples) or not len(points):
        return points
    apart = np.linalg.norm(points[:, None] - samples[None], axis=2)  # (P, S)
    nearest = apart.argmin(axis=0)
    return np.delete(points, np.unique(nearest[apart[nearest, np.arange(len(samples))] <= SAME_SAMPLE_MM]), axis=0)
