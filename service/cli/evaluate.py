"""``markerflow eval``: a scenario on labeled trajectories, scored."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from service.capture.formulation_spec import formulation_from_spec, formulation_from_table
from service.cli.report import print_summary, window_progress
from service.evaluation.cameras import evaluate_cameras
from service.evaluation.cloud import evaluate
from service.evaluation.scenario import Scenario
from service.io.formats import read_labeled
from service.labeling.cloud import CloudLabeler


def run_eval(trajectories: Path, scenario_path: Path, formulation: str | None, window: int | None, as_json: bool) -> None:
    """Simulate, label and score; print a table or one JSON object."""
    scenario = Scenario.from_toml(scenario_path)
    if window is not None:
        scenario = dataclasses.replace(scenario, window=window)
    if formulation is not None:
        chosen = formulation_from_spec(formulation)
    else:
        chosen = formulation_from_table({"name": scenario.formulation, **scenario.formulation_parameters}, str(scenario_path))
    labeler = CloudLabeler(formulation=chosen, window=scenario.window)
    truth = read_labeled(trajectories)
    with window_progress(f"labeling {trajectories.name}") as progress:
        if scenario.mode == "cameras":
            result = evaluate_cameras(truth, scenario, labeler, progress=progress)
        else:
            result = evaluate(truth, scenario, labeler, progress=progress)
    if as_json:
        print(json.dumps(result.summary(), allow_nan=False))
    else:
        print_summary(result.summary(), f"{trajectories.name} · {scenario_path.name}")
