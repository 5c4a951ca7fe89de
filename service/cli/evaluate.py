"""``markerflow eval``: a scenario on labeled trajectories, scored."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from service.capture.formulation_spec import formulation_from_spec, resolve_formulation
from service.capture.model_input import read_model
from service.cli.report import print_summary, warn, warn_doubtful, window_progress
from service.errors import InputError
from service.evaluation.cameras import CameraEvaluation, evaluate_cameras
from service.evaluation.cloud import Evaluation, evaluate
from service.evaluation.model_start import evaluate_from_model
from service.evaluation.scenario import Scenario
from service.io.formats import read_labeled
from service.labeling.result_warnings import time_limit_warning
from service.labeling.stats import doubtful_fraction
from service.labeling.take_warnings import take_scale_warning


def run_eval(
    trajectories: Path, scenario_path: Path, formulation: str | None, window: int | None, as_json: bool,
    model: Path | None = None,
) -> None:
    """Simulate, label and score; print a table or one JSON object, and warn on stderr when
    many labels are doubtful (``doubtful_fraction``; None in camera mode, whose evaluation
    keeps no labeled trajectories). ``model`` labels from a subject model, no labeled frame."""
    scenario = Scenario.from_toml(scenario_path)
    if model is not None:
        scenario = dataclasses.replace(scenario, first_frame="model")
    elif scenario.first_frame == "model":
        raise InputError(f"{scenario_path.name}: first_frame = \"model\" needs --model subject.json")
    if window is not None:
        scenario = dataclasses.replace(scenario, window=window)
    # Resolved here so that a bad formulation names the option or scenario file it came from.
    if formulation is not None:
        chosen = formulation_from_spec(formulation)
    else:
        chosen = resolve_formulation(scenario.formulation_table, str(scenario_path))
    # unlabeled trajectories *N name no marker; a marker never placed has nothing to score
    truth, never = read_labeled(trajectories).without_unlabeled().without_never_seen()
    if never:
        warn(f"warning: {len(never)} marker{'s' if len(never) > 1 else ''} with no position in any frame left out: "
             f"{', '.join(never[:6])}{' ...' if len(never) > 6 else ''}")
    warn(take_scale_warning(truth))
    result: Evaluation | CameraEvaluation
    with window_progress(f"labeling {trajectories.name}") as progress:
        if model is not None:
            result = evaluate_from_model(truth, scenario, read_model(model), chosen, progress, trajectories.name)
        elif scenario.mode == "cameras":
            result = evaluate_cameras(truth, scenario, chosen, progress=progress)
        else:
            result = evaluate(truth, scenario, chosen, progress=progress)
    doubtful = None
    if isinstance(result, Evaluation):
        doubtful = doubtful_fraction(result.result.confidence, result.result.occluded)
    summary = {**result.summary(), "doubtful_fraction": doubtful}
    if as_json:
        print(json.dumps(summary, allow_nan=False))
    else:
        print_summary(summary, f"{trajectories.name} · {scenario_path.name}")
    # the share the table's "scored frames" row shows (frame 0, the user's, not counted)
    share = summary.get("doubtful_share")
    warn_doubtful(share if isinstance(share, float) else doubtful)
    warn(time_limit_warning([w.status for w in result.windows]))
