"""Fit the reported confidence's calibration on the accuracy matrix's tuning half; check it on the validation half.

Each cell (recording x condition x seed, lp-l1, as ``bench/accuracy_matrix.py`` runs it) is
labeled as ``CaptureLabeling.label`` does (second pass included), and every label's raw
confidence (``CaptureLabeling.result(..., calibrated=False)``) is paired with whether the
point it names is the marker's own. The tuning half's pairs are fitted (``fit_calibration``); both halves are
then scored raw and calibrated: doubtful share and recall (raw p below ``DOUBTFUL_BELOW``,
the same labels as calibrated p below its image, and for comparison calibrated p below
``DOUBTFUL_BELOW``), Brier score, and the expected calibration error over ten bins of p; and
so is the map in use, ``LABEL_CALIBRATION``, so that it can be checked on other seeds than it
was fitted on (``--seeds 1 2``); and the confidence a result reports (the map in use, then lone
labels and shape breaks capped: ``service.labeling.reported``, ``shape_doubt``). The fitted knots are printed in the form of
``LABEL_CALIBRATION`` (``formulations/confidence/calibration.py``).

    .venv/bin/python bench/confidence_calibration.py [--seeds 0] [--frames 600] [--jobs 2] [--conditions ...]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.confidence.calibration import LABEL_CALIBRATION, ConfidenceCalibration, fit_calibration  # noqa: E402
from service.evaluation.matrix import CONDITIONS, DATA, RECORDINGS, prepare, recording_named  # noqa: E402
from service.evaluation.simulate_cloud import simulate_cloud  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402
from service.labeling.reported import as_reported  # noqa: E402
from service.labeling.stats import DOUBTFUL_BELOW, REPORTED_DOUBTFUL_BELOW  # noqa: E402

FIVE = ["default", "noise-2", "noise-4", "drop-30", "ghosts-10"]  # the conditions the matrices in docs/ run


def cell_labels(recording: str, condition: str, seed: int, frames: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(L,)`` raw and reported confidence and right of every window label of one cell."""
    take = prepare(recording_named(recording), DATA)
    scenario = replace(CONDITIONS[condition], seed=seed, start_frame=take.start, frames=min(frames, take.frames))
    simulated = simulate_cloud(take.truth, scenario)
    labeling = CaptureLabeling(simulated.capture(), scenario.labeling_options("lp-l1"))
    outcomes = labeling.refine(list(labeling.windows()))
    assert outcomes is not None  # no stop was asked for
    result = labeling.result(outcomes, calibrated=False)
    # the raw result as reported, not a second ``result``: that would assemble the take again
    reported = as_reported(replace(result, confidence=result.confidence.copy()))[0].confidence
    raw, shown, right = [], [], []
    for f in range(1, result.n_frames):  # frame 0 is the user's
        taken = result.point_index[f]
        labeled = np.flatnonzero(taken >= 0)
        raw.append(result.confidence[f, labeled])
        shown.append(reported[f, labeled])
        right.append(simulated.point_marker[f][taken[labeled]] == labeled)
    return np.concatenate(raw), np.concatenate(shown), np.concatenate(right)


def scores(p: np.ndarray, right: np.ndarray, below: float) -> str:
    """Doubtful share and recall below ``below``, Brier score and expected calibration error (ten bins)."""
    doubtful, wrong = p < below, ~right
    bins = np.clip((p * 10).astype(int), 0, 9)
    ece = sum(abs(right[bins == b].mean() - p[bins == b].mean()) * (bins == b).mean() for b in range(10) if (bins == b).any())
    recall = f"{(doubtful & wrong).sum() / wrong.sum():.3f}" if wrong.any() else "- (no label wrong)"
    return (f"doubtful below {below:.4f} {doubtful.mean():6.2%}, recall {recall}, "
            f"Brier {np.mean((p - right) ** 2):.4f}, calibration error {ece:.4f}")


def _cell(args: tuple[str, str, int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return cell_labels(*args)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--conditions", nargs="+", default=FIVE, choices=list(CONDITIONS))
    args = parser.parse_args()
    pooled: dict[str, tuple[np.ndarray, ...]] = {}
    with Pool(args.jobs) as pool:
        for half in ("tuning", "validation"):
            cells = [(r.name, c, s, args.frames) for r in RECORDINGS if r.half == half for c in args.conditions
                     for s in args.seeds]
            labeled = pool.map(_cell, cells)
            pooled[half] = tuple(np.concatenate(part) for part in zip(*labeled))
            print(f"{half}: {len(cells)} cells, {len(pooled[half][0]):,} labels, {1 - pooled[half][2].mean():.2%} wrong",
                  flush=True)
    calibration = fit_calibration(pooled["tuning"][0], pooled["tuning"][2])
    reported_below = float(calibration(DOUBTFUL_BELOW))  # the same labels flagged (the map is monotone)
    for half, (raw, reported, right) in pooled.items():
        print(f"{half:10s} raw        {scores(raw, right, DOUBTFUL_BELOW)}")
        print(f"{half:10s} calibrated {scores(calibration(raw), right, reported_below)}")
        print(f"{half:10s} calibrated {scores(calibration(raw), right, DOUBTFUL_BELOW)} (another threshold)")
        print(f"{half:10s} shipped    {scores(LABEL_CALIBRATION(raw), right, REPORTED_DOUBTFUL_BELOW)} (the map in use)")
        print(f"{half:10s} reported   {scores(reported, right, REPORTED_DOUBTFUL_BELOW)} (as a result reports it)")
    print(knots(calibration))


def knots(calibration: ConfidenceCalibration) -> str:
    """The calibration as the source holds it, runs of equal values merged to their ends."""
    raw, right = np.array(calibration.raw), np.array(calibration.right)
    keep = np.r_[True, (right[1:-1] != right[:-2]) | (right[1:-1] != right[2:]), True]
    return (f"LABEL_CALIBRATION = ConfidenceCalibration(\n    raw=({', '.join(f'{v:.5g}' for v in raw[keep])}),\n"
            f"    right=({', '.join(f'{v:.5g}' for v in right[keep])}),\n)")


if __name__ == "__main__":
    main()
