"""What a candidate generator hands the window builder."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from formulations.window.likelihood import CandidateLikelihood


@dataclass(frozen=True)
class WindowCandidates:
    """Candidate observations of every object in every frame of one window.

    Frames are numbered 1..M; frame 0 is the template (the last frame of the previous
    window, or the labeled first frame).

    Attributes:
        template_location: ``(N, D)`` location of each object at the template frame.
        template_occluded: ``(N,)`` True where the object was not seen at the template.
        n_frames: M.
        object: ``(C,)`` object of each candidate.
        frame: ``(C,)`` frame 1..M of each candidate.
        location: ``(C, D)`` location vector r of each candidate.
        template_cost: ``(C,)`` g(s_n, v): cost of the candidate against the template.
        resources: ``(C, R)`` sparse 0/1, what each candidate consumes (point ids,
            (camera, detection) pairs); shared resources make conflict groups.
        occlusion_location: ``(N, M, D)`` location the layout term assumes while occluded.
        motion: ``(N, M, D)`` expected displacement of each object into each frame; NaN
            where unknown (the displacement term is then left out).
        appearance: ``(C, H)`` normalised histograms, or None.
        template_appearance: ``(N, H)`` histograms of the templates, or None.
        likelihood: Negative log-likelihood costs that replace the weights' constants
            (``likelihood``), or None for Jiang's weighted costs.
    """

    template_location: np.ndarray
    template_occluded: np.ndarray
    n_frames: int
    object: np.ndarray
    frame: np.ndarray
    location: np.ndarray
    template_cost: np.ndarray
    resources: sp.csr_matrix
    occlusion_location: np.ndarray
    motion: np.ndarray
    appearance: np.ndarray | None = None
    template_appearance: np.ndarray | None = None
    likelihood: CandidateLikelihood | None = None

    @property
    def n_objects(self) -> int:
        return int(self.template_location.shape[0])

    def __post_init__(self) -> None:
        n, m, c = self.n_objects, self.n_frames, len(self.object)
        if m < 1:
            raise ValueError(f"a window needs at least one frame after the template, got {m}")
        if len(self.frame) != c or self.location.shape[0] != c or len(self.template_cost) != c:
            raise ValueError("candidate arrays object/frame/location/template_cost differ in length")
        if self.resources.shape[0] != c:
            raise ValueError(f"resources has {self.resources.shape[0]} rows for {c} candidates")
        if c and (self.frame.min() < 1 or self.frame.max() > m):
            raise ValueError(f"candidate frames must lie in 1..{m}")
        if c and (self.object.min() < 0 or self.object.max() >= n):
            raise ValueError(f"candidate objects must lie in 0..{n - 1}")
        if self.occlusion_location.shape[:2] != (n, m) or self.motion.shape[:2] != (n, m):
            raise ValueError("occlusion_location and motion must be (objects, frames, D)")
        if not np.isfinite(self.location).all() or not np.isfinite(self.template_cost).all():
            raise ValueError("candidate locations and template costs must be finite")
