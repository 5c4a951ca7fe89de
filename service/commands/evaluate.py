"""``markerflow eval``: a scenario on labeled trajectories, scored."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from service.commands.report import out, print_summary, window_progress
from service.evaluation import evaluate
from service.formats import read_labeled
from service.scenario import Scenario


def run_eval(trajectories: Path, scenario_path: Path, formulation: str | None, window: int | None, as_json: bool) -> None:
    """Simulate, label and score; print a table or one JSON object."""
    scenario = Scenario.from_toml(scenario_path)
    overrides = {k: v for k, v in (("formulation", formulation), ("window", window)) if v is not None}
    scenario = dataclasses.replace(scenario, **overrides)
    truth = read_labeled(trajectories)
    with window_progress(f"labeling {trajectories.name}") as progress:
        result = evaluate(truth, scenario, progress=progress)
    if as_json:
        print(json.dumps(result.summary()))
    else:
        print_summary(result.summary(), f"{trajectories.name} · {scenario_path.name}")
