"""Per-window statistics kept by the labeler: the certificate and where the time went."""

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


def certificate_figures(windows: list[WindowStats]) -> dict[str, float | None]:
    """Integral fraction and gap median/max over a run's windows."""
    gaps = np.array([w.gap for w in windows]) if windows else np.zeros(1)
    return {
        "integral_window_fraction": float(np.mean([w.integral for w in windows])) if windows else 1.0,
        "gap_median": finite_or_none(np.median(gaps)),
        "gap_max": finite_or_none(np.max(gaps)),
    }
