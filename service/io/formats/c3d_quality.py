"""Each label, and each unlabeled ``*N`` sample, keeps the measurement quality of the input
sample it is.

A C3D copy's points hold the input's own samples: a label is the point a marker took, a
``*N`` sample a point none took (or an input sample outside the labeled frames). The
residual and camera mask the capture system gave that sample describe the measurement, not
the name, so they go with the sample wherever the labels put it. Residual 0 would tell Nexus
or Visual3D that the sample was gap-filled, and a cleared mask that no camera saw it. A
sample matching no input sample of its frame gets residual 0 and no camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SAME_SAMPLE = 1e-6  # in the file's unit: one input sample written back through mm (round off ~1e-12)
# (labels, points, frames) distances matched at a time. The (3, labels, points, frames)
# differences and the norm's temporaries take ~50 bytes per distance: 2,000,000 made a C3D
# output's peak (555 MB at 135_02 tiled to 10,000 frames, 125 MB of it here); 250,000 is ~12 MB.
CHUNK_SAMPLES = 250_000


@dataclass(frozen=True)
class SampleQuality:
    """The input's samples and their quality, before the labels replace any point.

    Attributes:
        points: ``(3, P, F)`` in the file's unit.
        residuals: ``(P, F)``; negative where the sample is missing.
        masks: ``(C, P, F)`` camera masks, or None when the file has none.
    """

    points: np.ndarray
    residuals: np.ndarray
    masks: np.ndarray | None

    @classmethod
    def of(cls, points: np.ndarray, meta: dict, copied: bool = True) -> SampleQuality:
        """Of a C3D's ``points`` and ``meta_points``: copies, or (``copied`` False, for arrays
        nothing writes into) the arrays themselves."""
        masks = meta.get("camera_masks")
        held = np.copy if copied else np.asarray
        return cls(held(points[:3]), held(meta["residuals"][0]), held(masks) if masks is not None and masks.size else None)

    def taken(self, values: np.ndarray, start: int) -> tuple[np.ndarray, np.ndarray | None]:
        """For labels ``values`` ``(3, M, F')`` (the file's unit, NaN where hidden) from frame
        ``start``: ``(M, F')`` residuals and ``(C, M, F')`` camera masks of the samples they took."""
        match = self._matches(values, start)
        frames = np.arange(values.shape[2])[None] + start
        found = match >= 0
        residuals = np.where(found, self.residuals[np.maximum(match, 0), frames], 0.0)
        if self.masks is None:
            return residuals, None
        return residuals, np.where(found[None], self.masks[:, np.maximum(match, 0), frames], False)

    def _matches(self, values: np.ndarray, start: int) -> np.ndarray:
        """``(M, F')`` the input column holding each label's sample in its frame, -1 for none."""
        match = np.full(values.shape[1:], -1)
        step = max(1, CHUNK_SAMPLES // max(1, values.shape[1] * self.points.shape[1]))
        for first in range(0, values.shape[2], step):
            span = slice(first, min(first + step, values.shape[2]))
            given = self.points[:, :, start + span.start : start + span.stop]  # (3, P, f)
            gap = np.linalg.norm(values[:, :, None, span] - given[:, None], axis=0)  # (M, P, f)
            valid = self.residuals[None, :, start + span.start : start + span.stop] >= 0
            gap = np.where(valid & np.isfinite(gap), gap, np.inf)
            nearest = np.argmin(gap, axis=1)  # (M, f)
            match[:, span] = np.where(np.take_along_axis(gap, nearest[:, None], axis=1)[:, 0] < SAME_SAMPLE, nearest, -1)
        return match
