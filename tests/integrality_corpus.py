"""The fixed corpus of the integrality regression: windows and how lp-l1 does on them.

Run ``python tests/integrality_corpus.py`` to print the figures and rewrite
``fixtures/integrality.json`` (only when a change is meant to move the baseline).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[1]))

from formulations.lp_l1 import LpL1  # noqa: E402
from formulations.network import build_window  # noqa: E402
from service.jiang_instance import jiang_instance  # noqa: E402
from windows import random_window  # noqa: E402

FIXTURE = Path(__file__).parent / "fixtures" / "integrality.json"


def corpora() -> dict[str, list]:
    """Named lists of windows: generated at several sizes, with and without layout."""
    instances = [jiang_instance(n_frames=10, n_observations=12, seed=s) for s in range(8)]
    jiang = [build_window(i.candidates, i.weights)[0] for i in instances]
    return {
        "jiang-10x12-mu0": jiang,
        "random-3x4-mu0": [random_window(s, n_objects=3, n_frames=4, n_points=4, per_object=3) for s in range(30)],
        "random-3x3-mu0.3": [random_window(s, n_objects=3, n_frames=3, n_points=4, per_object=2, mu=0.3) for s in range(30)],
    }


def measure(windows: list) -> dict[str, float]:
    solutions = [LpL1(decompose=False).solve(w) for w in windows]
    gaps = np.array([s.gap for s in solutions])
    return {
        "windows": len(windows),
        "integral_fraction": float(np.mean([s.integral for s in solutions])),
        "gap_median": float(np.median(gaps)),
        "gap_max": float(gaps.max()),
    }


if __name__ == "__main__":
    figures = {name: measure(windows) for name, windows in corpora().items()}
    print(json.dumps(figures, indent=2))
    FIXTURE.write_text(json.dumps(figures, indent=2) + "\n")
