"""Build the integrality corpus: windows saved as fixture files with their recorded figures.

    .venv/bin/python tests/integrality_corpus.py

writes ``tests/fixtures/integrality/<corpus>/<n>.npz`` and ``recorded.json`` (per window:
the LP objective, whether the LP optimum was integral, the rounded cost and the ILP
optimum). Run it only when a change is meant to move the baseline; the regression test
and ``markerflow integrality`` read what it wrote.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from windows import random_window  # noqa: E402

from formulations.methods.registry import get_formulation  # noqa: E402
from formulations.relaxation.components import coupled_components, restrict  # noqa: E402
from formulations.relaxation.viterbi import shortest_paths  # noqa: E402
from formulations.window.build import build_window  # noqa: E402
from formulations.window.objective import conflicts  # noqa: E402
from service.evaluation.integrality import RECORD  # noqa: E402
from service.evaluation.jiang_instance import jiang_instance  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.io.window_files import save_window  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

FOLDER = ROOT / "tests" / "fixtures" / "integrality"
DATA = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart"
LP = get_formulation("lp-l1", decompose=False)


def generated() -> dict[str, list]:
    """Generated windows across sizes and clutter."""
    jiang = [jiang_instance(n_frames=10, n_observations=k, seed=s) for k in (8, 16, 24) for s in range(5)]
    return {
        "random-3x4": [random_window(s, n_objects=3, n_frames=4, n_points=4, per_object=3) for s in range(20)],
        "jiang-3x10-clutter": [build_window(i.candidates, i.weights)[0] for i in jiang],
        "random-3x3-layout": [random_window(s, n_objects=3, n_frames=3, n_points=4, per_object=2, mu=0.3) for s in range(20)],
    }


def from_recording(name: str, seeds: range, frames: int, limit: int) -> list:
    """Coupled components whose objects' Viterbi paths collide: what reaches the LP."""
    truth = read_labeled(DATA / name)
    found: list = []

    def keep(_template, problem, _solution) -> None:
        label = coupled_components(problem)
        colliding = set(problem.node_object[problem.conflict_groups[conflicts(problem, shortest_paths(problem)[0])].indices])
        for component in {label[o] for o in colliding}:
            found.append(restrict(problem, np.flatnonzero(label == component))[0])

    for seed in seeds:
        simulated = simulate_cloud(truth, Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10,
                                                 ghosts_per_frame=2.0, seed=seed, frames=frames))
        CaptureLabeling(simulated.capture()).label(observer=keep)
    return found[:limit]


def record(name: str, windows: list) -> list[dict]:
    ilp = get_formulation("ilp", decompose=False, time_limit=300.0)
    folder = FOLDER / name
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for i, problem in enumerate(windows):
        file = f"{name}/{i:03d}.npz"
        save_window(FOLDER / file, problem)
        lp, exact = LP.solve(problem), ilp.solve(problem)
        assert exact.integral, f"{file}: ILP not proven optimal ({exact.status})"
        rows.append({"file": file, "lp_objective": lp.lower_bound, "lp_integral": lp.integral,
                     "rounded_cost": lp.cost, "ilp_optimum": exact.cost})
    return rows


if __name__ == "__main__":
    corpora = generated() | {
        "cmu-85-02-cloud": from_recording("85_02.c3d", range(2), 0, 30),
        "cmu-135-02-cloud": from_recording("135_02.c3d", range(1), 1500, 30),
    }
    recorded = {name: record(name, windows) for name, windows in corpora.items()}
    (FOLDER / RECORD).write_text(json.dumps(recorded, indent=1) + "\n")
    for name, rows in recorded.items():
        print(f"{name:22s} {len(rows):3d} windows, LP integral {np.mean([r['lp_integral'] for r in rows]):.0%}")
