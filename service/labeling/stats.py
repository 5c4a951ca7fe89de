"""Per-window statistics kept by the labeler: the certificate, where the time went, and
which labels the certificate does not vouch for.

An integral window is optimal *under the model* (the arc costs and gates of the window
LP): it proves no label right. Labels are called doubtful where the model had the least
to go on, and a take's share of them is reported next to the certificate.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from formulations.window.solution import WindowSolution


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

    @classmethod
    def of(cls, template: int, last: int, solution: WindowSolution, prepare: float, total: float) -> WindowStats:
        return cls(
            template=template, last=last, integral=solution.integral, gap=solution.gap,
            cost=solution.cost, lower_bound=solution.lower_bound, n_fractional=solution.n_fractional,
            status=solution.status, prepare_seconds=prepare, build_seconds=solution.build_seconds,
            solve_seconds=solution.solve_seconds, round_seconds=solution.round_seconds,
            total_seconds=total, components=dict(solution.components),
        )

    def to_dict(self) -> dict:
        return asdict(self)


def finite_or_none(value: float) -> float | None:
    """JSON has no inf: a figure nothing proved (a heuristic's gap) becomes None."""
    return float(value) if np.isfinite(value) else None


REACQUIRED_FRAMES = 5  # a label stays doubtful this many frames after its marker reappears
DOUBTFUL_WARNING = 0.02  # warn when more than this share of a take's labels is doubtful
REACQUIRED_LISTED = 20  # re-acquisition frames listed per marker in a summary


def reacquired(occluded: np.ndarray, frames: int = REACQUIRED_FRAMES) -> np.ndarray:
    """``(F, M)`` bool: seen in frame ``f`` and occluded in one of frames ``f - frames .. f - 1``.

    Such a label was picked up again rather than carried along a track: the marker state
    that chose it had been predicted, unseen, through the gap.
    """
    recent = np.zeros_like(occluded, dtype=bool)
    for back in range(1, frames + 1):
        recent[back:] |= occluded[:-back]
    return recent & ~occluded


def doubtful_labels(occluded: np.ndarray, windows: list[WindowStats]) -> np.ndarray:
    """``(F, M)`` bool: labels (seen samples) that are ``reacquired``, or that lie in a window
    whose relaxation was fractional (rounded, so not even optimal under the model)."""
    fractional = np.zeros(len(occluded), dtype=bool)
    for w in windows:
        fractional[w.template + 1 : w.last + 1] |= not w.integral
    return reacquired(occluded) | (fractional[:, None] & ~occluded)


def doubtful_fraction(occluded: np.ndarray, windows: list[WindowStats]) -> float:
    """Doubtful labels / labels (``doubtful_labels``; 0 with no label)."""
    occluded = np.asarray(occluded, dtype=bool)
    labels = int((~occluded).sum())
    return int(doubtful_labels(occluded, windows).sum()) / labels if labels else 0.0


def reacquisitions(names: list[str], occluded: np.ndarray) -> dict[str, list[int]]:
    """Per marker that has any, the first ``REACQUIRED_LISTED`` frames (from 0) where it
    reappeared after an occlusion: where its identity went from predicted back to a point."""
    onsets = reacquired(np.asarray(occluded, dtype=bool), frames=1)
    return {
        name: np.flatnonzero(onsets[:, m])[:REACQUIRED_LISTED].tolist()
        for m, name in enumerate(names) if onsets[:, m].any()
    }


def certificate_figures(windows: list[WindowStats]) -> dict[str, float | None]:
    """Integral fraction and gap median/max over a run's windows."""
    gaps = np.array([w.gap for w in windows]) if windows else np.zeros(1)
    return {
        "integral_window_fraction": float(np.mean([w.integral for w in windows])) if windows else 1.0,
        "gap_median": finite_or_none(np.median(gaps)),
        "gap_max": finite_or_none(np.max(gaps)),
    }
