"""Labeling with no labeled frame, from a subject model: a table over real takes.

Rows, each labeled by markerflow from a model and, where a complete first frame exists, the
same scenario from a labeled first frame:

- template: a marker-set template + the static trial -> the dynamic take of the same subject
  (1 mm noise, 10 % deletions in 10-frame bursts, 2 ghosts/frame; configs/scenarios/model_start.toml);
- half: a model fitted on the first part of a take labels the rest (same scenario);
- real: the takes refused today (no complete first frame): a model fitted on their first
  half labels the second half as recorded (real gaps, no simulation), from its first frame,
  where not every marker is visible; accuracy against the file's own labels.

    .venv/bin/python bench/model_start.py [--cap 1200]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.errors import FormulationError  # noqa: E402
from formulations.subject.fit import fit_subject  # noqa: E402
from formulations.subject.template import fit_template  # noqa: E402
from service.capture.capture import Capture  # noqa: E402
from service.capture.markerset import load_template  # noqa: E402
from service.capture.model_input import model_names  # noqa: E402
from service.errors import InputError  # noqa: E402
from service.evaluation.cloud import evaluate  # noqa: E402
from service.evaluation.model_start import evaluate_from_model  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

DATA = ROOT.parent / "shared" / "data"
SCENARIO = ROOT / "configs" / "scenarios" / "model_start.toml"
TEMPLATES = [
    ("rajagopal", "mocap_opensim/rajagopal_static_run.trc", "mocap_opensim/rajagopal_motion_capture_run.trc"),
    ("gait2354", "mocap_opensim/gait2354_subject01_static.trc", "mocap_opensim/gait2354_subject01_walk1.trc"),
]
HALVES = ["c3d_mocaprecovery_cmu_hdm05_numediart/85_02.c3d", "c3d_mocaprecovery_cmu_hdm05_numediart/135_02.c3d"]
REFUSED = [
    "c3d_ezc3d_testfiles/BTS.c3d", "c3d_mocaprecovery_cmu_hdm05_numediart/03_rolling.c3d",
    "c3d_kineticstoolkit/kinematics_basket_sprint.c3d", "c3d_kineticstoolkit/kinematics_racing_full.c3d",
    "mocap_opensim/opensim-core_walking2.c3d", "mocap_opensim/hamner_subject02_running.trc",
]


def present(path: str) -> tuple[list[str], np.ndarray, float]:
    take = read_labeled(DATA / path)
    return take.names, np.where(take.missing()[:, :, None], np.nan, take.positions), take.rate


def simulated_pair(truth_path: str, model, scenario: Scenario) -> str:
    truth = read_labeled(DATA / truth_path)
    by_model = evaluate_from_model(truth, scenario, model)
    by_frame = evaluate(truth, dataclasses.replace(scenario, first_frame="labeled"))
    a, b = by_model.scores.label_accuracy, by_frame.scores.label_accuracy
    return f"{a:.3%} | {b:.3%} | {100 * (a - b):+.3f} | {filled_rmse(by_model, model)}"


def filled_rmse(run, model) -> str:
    """RMSE and median (mm) of the fill against the clean truth, markers on segments of three or more."""
    rigid = {m for s in model.segments if len(s.markers) >= 3 for m in s.markers}
    truth = run.capture.truth
    columns = [i for i, n in enumerate(run.result.names) if n in rigid]
    true = truth.positions[:, [truth.names.index(run.result.names[i]) for i in columns]]
    error = np.linalg.norm(run.result.filled[:, columns] - true, axis=2)
    error = error[1:][run.result.occluded[1:, columns] & np.isfinite(error[1:])]
    return f"{np.sqrt(np.mean(error**2)):.1f} / {np.median(error):.1f}" if error.size else "-"


def real_take(path: str) -> str:
    names, positions, rate = present(path)
    half = len(positions) // 2
    try:
        model = fit_subject(names, positions[:half]).model
    except FormulationError as error:
        return f"fit refused: {error}"[:160]
    order = model_names(model)
    columns = [names.index(n) for n in order]
    rng = np.random.default_rng(0)
    frames, owners = [], []
    for frame in positions[half:, columns]:
        seen = np.flatnonzero(np.isfinite(frame).all(axis=1))
        shuffle = rng.permutation(len(seen))
        frames.append(frame[seen][shuffle])
        owners.append(seen[shuffle])
    capture = Capture(order, np.full((len(order), 3), np.nan), rate, points=frames, model=model)
    try:
        result, _ = CaptureLabeling(capture).label()
    except InputError as error:
        return f"refused: {error}"[:160]
    took = result.point_index
    right = sum(int((owners[f][took[f][took[f] >= 0]] == np.flatnonzero(took[f] >= 0)).sum()) for f in range(len(frames)))
    visible = sum(len(o) for o in owners)
    first_seen = len(owners[0])
    return (f"{right / visible:.2%} of {visible} visible marker-frames; model {len(order)} of {len(names)} markers, "
            f"{first_seen} visible in the start frame")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--cap", type=int, default=1200, help="frames to fit on and to label, per half")
    args = parser.parse_args()
    scenario = Scenario.from_toml(SCENARIO)
    print("| take | from model | from a labeled frame | difference (pt) | fill RMSE / median (mm) |\n|---|---|---|---|---|")
    for markerset, static, dynamic in TEMPLATES:
        names, positions, _ = present(static)
        model = fit_template(load_template(markerset), names, positions)
        row = simulated_pair(dynamic, model, dataclasses.replace(scenario, start_frame=0, frames=0))
        print(f"| {markerset}: {Path(static).name} -> {Path(dynamic).name} | {row} |")
    for path in HALVES:
        names, positions, _ = present(path)
        half = min(len(positions) // 2, args.cap)
        model = fit_subject(names, positions[:half]).model
        start = len(positions) // 2
        frames = min(len(positions) - start, args.cap)
        row = simulated_pair(path, model, dataclasses.replace(scenario, start_frame=start, frames=frames))
        print(f"| {Path(path).name}: fit frames 0-{half - 1}, label {start}-{start + frames - 1} | {row} |")
    print("\n| refused take | second half, labeled from a model of the first half |\n|---|---|")
    for path in REFUSED:
        print(f"| {Path(path).name} | {real_take(path)} |", flush=True)


if __name__ == "__main__":
    main()
