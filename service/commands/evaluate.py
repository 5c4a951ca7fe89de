"""``markerflow eval``: a scenario on labeled trajectories, scored."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from service.commands.report import print_summary, window_progress
from service.cloud_labeler import CloudLabeler
from service.evaluation import evaluate
from service.formulation_spec import formulation_from_spec
from service.formats import read_labeled
from service.scenario import Scenario


def run_eval(trajectories: Path, scenario_path: Path, formulation: str | None, window: int | None, as_json: bool) -> None:
    """Simulate, label and score; print a table or one JSON object."""
    scenario = Scenario.from_toml(scenario_path)
    if window is not None:
        scenario = dataclasses.replace(scenario, window=window)
    labeler = None
    if formulation is not None:
        labeler = CloudLabeler(formulation=formulation_from_spec(formulation), window=scenario.window)
    truth = read_labeled(trajectories)
    with window_progress(f"labeling {trajectories.name}") as progress:
        result = evaluate(truth, scenario, labeler, progress=progress)
    if as_json:
        print(json.dumps(result.summary(), allow_nan=False))
    else:
        print_summary(result.summary(), f"{trajectories.name} · {scenario_path.name}")
