"""A window's certificate survives from the formulation's solution to WindowStats and to eval's figures.

Real windows of these recordings are integral (gap 0), so nothing would notice a gap lost
on the way. A test double makes every window after the first fractional, with a known certificate.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np
import pytest
from capture_fixtures import CMU, POSE2SIM, points_capture

from formulations.methods.formulation import Formulation
from formulations.methods.lp_l1 import LpL1
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.capture.capture import LabelingOptions
from service.evaluation.cameras import evaluate_cameras
from service.evaluation.cloud import evaluate
from service.evaluation.scenario import Scenario
from service.io.formats import read_labeled
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.outcome import WindowOutcome


@dataclass(frozen=True)
class FractionalAfterFirst(Formulation):
    """lp-l1's paths; the certificate of window k >= 1 is made fractional, with gap 5 % k.

    ``returned`` keeps every solution it gave, in order (the list itself is not frozen).
    """

    name: ClassVar[str] = "fractional-after-first"
    returned: list[WindowSolution] = field(default_factory=list)

    def solve(self, problem: WindowProblem) -> WindowSolution:
        solution = LpL1().solve(problem)
        k = len(self.returned)
        if k:
            bound = solution.cost - 0.05 * k * max(abs(solution.cost), 1.0)
            solution = replace(solution, lower_bound=bound, integral=False, n_fractional=k)
        self.returned.append(solution)
        return solution


def test_window_stats_carry_the_solutions_certificate():
    formulation = FractionalAfterFirst()
    observed: list[WindowSolution] = []
    labeling = CaptureLabeling(points_capture(frames=120), LabelingOptions(formulation=formulation))
    outcomes = list(labeling.windows(observer=lambda _template, _problem, solution: observed.append(solution)))
    assert len(outcomes) == len(formulation.returned) == 7  # 119 new frames, 19 a window
    assert all(a is b for a, b in zip(observed, formulation.returned))
    for outcome, solution in zip(outcomes, formulation.returned):
        stats = outcome.stats
        assert (stats.integral, stats.gap, stats.lower_bound, stats.cost, stats.n_fractional) == (
            solution.integral, solution.gap, solution.lower_bound, solution.cost, solution.n_fractional)
    assert [s.integral for s in formulation.returned] == [True] + [False] * 6
    assert [s.gap for s in formulation.returned] == pytest.approx([0.05 * k for k in range(7)])
    stored = WindowOutcome.from_bytes(outcomes[3].to_bytes()).stats  # what a job keeps
    assert stored.gap == formulation.returned[3].gap and not stored.integral


CLOUD = Scenario(frames=120, second_pass=False)  # one pass: the formulation's calls are the summary's windows
CAMERAS = Scenario(mode="cameras", calibration=str(POSE2SIM), frames=120)


@pytest.mark.parametrize(("scenario", "run"), [(CLOUD, evaluate), (CAMERAS, evaluate_cameras)], ids=["cloud", "cameras"])
def test_eval_figures_report_the_fractional_gap(scenario, run):
    formulation = FractionalAfterFirst()
    summary = run(read_labeled(CMU), scenario, formulation).summary()
    gaps = [s.gap for s in formulation.returned]
    assert gaps == pytest.approx([0.05 * k for k in range(7)])
    assert summary["gap_max"] == max(gaps) == gaps[6]
    assert summary["gap_median"] == np.median(gaps) == gaps[3]
    assert summary["integral_window_fraction"] == 1 / 7
    assert summary["formulation"] == "fractional-after-first"
