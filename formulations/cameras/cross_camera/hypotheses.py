"""Candidate cross-camera points: which detections each uses, and how well it fits them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Hypotheses:
    """Candidate points and how they fit their detections.

    Attributes:
        views: (H, C) global index of the detection used in camera c, -1 for none.
        frame: (H,) frame of the block.
        points: (H, 3) triangulated positions.
        projected: (H, C, 2) pixels of each point in every camera.
        residual: (H, C) pixel distance to the detection used, NaN where none.
        depth: (H, C) depth of each point in every camera.
    """

    views: np.ndarray
    frame: np.ndarray
    points: np.ndarray
    projected: np.ndarray
    residual: np.ndarray
    depth: np.ndarray

    def __len__(self) -> int:
        return len(self.views)

    @property
    def n_views(self) -> np.ndarray:
        """(H,) views each hypothesis uses."""
        n_views: np.ndarray = (self.views >= 0).sum(axis=1)
        return n_views

    @property
    def rms(self) -> np.ndarray:
        """(H,) root mean square residual over the views used, pixels."""
        rms: np.ndarray = np.sqrt(np.nansum(self.residual**2, axis=1) / np.maximum(self.n_views, 1))
        return rms

    def take(self, index: np.ndarray) -> Hypotheses:
        return Hypotheses(*(array[index] for array in self._arrays()))

    def replaced(self, index: np.ndarray, rows: Hypotheses) -> Hypotheses:
        """A copy whose rows ``index`` are ``rows``."""
        arrays = [array.copy() for array in self._arrays()]
        for array, new in zip(arrays, rows._arrays()):
            array[index] = new
        return Hypotheses(*arrays)

    def _arrays(self) -> tuple[np.ndarray, ...]:
        return self.views, self.frame, self.points, self.projected, self.residual, self.depth
