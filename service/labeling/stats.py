"""Per-window statistics kept by the labeler: the certificate, where the time went, and
which labels the certificate does not vouch for.

An integral window is optimal *under the model* (the arc costs and gates of the window
LP): it proves no label right. Every label also carries a confidence
(``formulations.confidence``: the margin by which the chosen reading beats the best
reading that changes the label, read as a probability); a label is *doubtful* when its
confidence is below ``DOUBTFUL_BELOW``, and a take's share of them is reported next to
the certificate. The windows' confidences are what labeling acts on; a result reports them
calibrated (``formulations.confidence.calibration``), where the same labels are doubtful
below ``REPORTED_DOUBTFUL_BELOW`` (the map is monotone).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from formulations.confidence.calibration import LABEL_CALIBRATION
from formulations.window.solution import WindowSolution

DOUBTFUL_BELOW = 0.9  # a label whose (window's, raw) confidence is below this is doubtful
REPORTED_DOUBTFUL_BELOW = float(LABEL_CALIBRATION(DOUBTFUL_BELOW))  # the same labels, calibrated as reported
DOUBTFUL_WARNING = 0.02  # warn when more than this share of a take's labels is doubtful
REACQUIRED_LISTED = 20  # re-acquisition frames listed per marker in a summary


@dataclass(frozen=True)
class DoubtCount:
    """A window's labels (markers holding a point or view), how many are doubtful, and the
    seconds their confidence took."""

    labels: int
    doubtful: int
    seconds: float

    @classmethod
    def of(cls, confidence: np.ndarray, occluded: np.ndarray, seconds: float) -> DoubtCount:
        return cls(int((~occluded).sum()), int(doubtful_labels(confidence, occluded).sum()), seconds)


@dataclass(frozen=True)
class WindowStats:
    """One window's certificate and timings.

    Attributes:
        template, last: First (template) and last frame of the window.
        integral: The relaxation's optimum was integral (the labels are globally optimal).
        gap: Relative gap between the rounded cost and the LP bound.
        cost, lower_bound: Objective of the returned paths and the proven bound.
        n_fractional: Fractional variables in the relaxation.
        status: Solver status.
        prepare_seconds: Candidates and network building.
        build_seconds, solve_seconds, round_seconds: Inside the formulation.
        total_seconds: Whole window, inversion included.
        components: How the window was split (objects by Viterbi, coupled components).
        labels, doubtful: Labels in the window's new frames, and those with a confidence
            below ``DOUBTFUL_BELOW`` (0 in windows stored before confidences existed).
        confidence_seconds: Time spent on the labels' confidence (in ``total_seconds``).
    """

    template: int
    last: int
    integral: bool
    gap: float
    cost: float
    lower_bound: float
    n_fractional: int
    status: str
    prepare_seconds: float
    build_seconds: float
    solve_seconds: float
    round_seconds: float
    total_seconds: float
    components: dict[str, int]
    labels: int = 0
    doubtful: int = 0
    confidence_seconds: float = 0.0

    @classmethod
    def of(
        cls, template: int, last: int, solution: WindowSolution, prepare: float, total: float, doubt: DoubtCount,
    ) -> WindowStats:
        return cls(
            template=template, last=last, integral=solution.integral, gap=solution.gap,
            cost=solution.cost, lower_bound=solution.lower_bound, n_fractional=solution.n_fractional,
            status=solution.status, prepare_seconds=prepare, build_seconds=solution.build_seconds,
            solve_seconds=solution.solve_seconds, round_seconds=solution.round_seconds,
            total_seconds=total, components=dict(solution.components), labels=doubt.labels,
            doubtful=doubt.doubtful, confidence_seconds=doubt.seconds,
        )

    def to_dict(self) -> dict:
        return asdict(self)


def finite_or_none(value: float) -> float | None:
    """JSON has no inf: a figure nothing proved (a heuristic's gap) becomes None."""
    return float(value) if np.isfinite(value) else None


def reacquired(occluded: np.ndarray) -> np.ndarray:
    """``(F, M)`` bool: seen in frame ``f`` and occluded in frame ``f - 1``: picked up again
    rather than carried along a track."""
    onsets = np.zeros_like(occluded, dtype=bool)
    onsets[1:] = occluded[:-1] & ~occluded[1:]
    return onsets


def doubtful_labels(confidence: np.ndarray, occluded: np.ndarray, below: float = DOUBTFUL_BELOW) -> np.ndarray:
    """``(F, M)`` bool: labels (seen samples) whose confidence is below ``below`` (windows' raw
    confidences: ``DOUBTFUL_BELOW``)."""
    return (np.asarray(confidence) < below) & ~np.asarray(occluded, dtype=bool)


def reported_doubtful(confidence: np.ndarray, occluded: np.ndarray) -> np.ndarray:
    """``doubtful_labels`` of a result's (calibrated) confidences: below ``REPORTED_DOUBTFUL_BELOW``."""
    return doubtful_labels(confidence, occluded, REPORTED_DOUBTFUL_BELOW)


def doubtful_fraction(confidence: np.ndarray, occluded: np.ndarray) -> float:
    """A result's doubtful labels / labels (``reported_doubtful``; 0 with no label)."""
    occluded = np.asarray(occluded, dtype=bool)
    labels = int((~occluded).sum())
    return int(reported_doubtful(confidence, occluded).sum()) / labels if labels else 0.0


def reacquisitions(names: list[str], occluded: np.ndarray) -> dict[str, list[int]]:
    """Per marker that has any, the first ``REACQUIRED_LISTED`` frames (from 0) where it
    reappeared after an occlusion: where its identity went from predicted back to a point."""
    return frames_listed(names, reacquired(np.asarray(occluded, dtype=bool)))


def frames_listed(names: list[str], marked: np.ndarray) -> dict[str, list[int]]:
    """Per marker with any ``marked`` ``(F, N)`` frame, the first ``REACQUIRED_LISTED`` of them (from 0)."""
    return {name: np.flatnonzero(marked[:, m])[:REACQUIRED_LISTED].tolist() for m, name in enumerate(names) if marked[:, m].any()}


def certificate_figures(windows: list[WindowStats]) -> dict[str, float | None]:
    """Integral fraction and gap median/max over a run's windows."""
    gaps = np.array([w.gap for w in windows]) if windows else np.zeros(1)
    return {
        "integral_window_fraction": float(np.mean([w.integral for w in windows])) if windows else 1.0,
        "gap_median": finite_or_none(np.median(gaps)),
        "gap_max": finite_or_none(np.max(gaps)),
    }
