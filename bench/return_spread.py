"""How far a marker comes back from its prediction, against the spread the labeler gives it.

A marker unseen for u frames is priced on its return by the density of its point under its
prediction, of per-axis variance ``MarkerState.prediction_var``: one frame's motion residual
plus a drift learned from earlier returns (``formulations/markers/motion.py``), one value for
every marker. Here a real take is labeled once (first pass only, from S, the first frame with
the most markers labeled, as ``bench/real_takes.py``) and every return the labeler's states see
is recorded: u, the squared error per axis |e|^2 / 3 off the prediction, and the variance it
was given. Returns are grouped by what carried the marker while unseen (at its return):

- carried: a firm rigid fit of seen neighbours (``MarkerState.carriers``);
- followed: its seen neighbours' motion, without a firm fit;
- stranded: nothing, a damped stale velocity.

Per group and gap length: returns, median error (mm, 3D), and z^2 = (|e|^2 / 3) / variance,
mean and median (a Gaussian of the given variance has mean 1 and median 0.79). The states
record no history, so ``MarkerState._advance`` is wrapped here to read each return as the
labeler computes it; the guide's advances are counted too (both follow the same rule).

    .venv/bin/python bench/return_spread.py [--only ktk-basket numediart-rolling] [--cap 1500]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.markers.means import axis_mean  # noqa: E402
from formulations.markers.state import MarkerState  # noqa: E402
from service.capture.capture import LabelingOptions  # noqa: E402
from service.capture.from_recording import capture_from_span  # noqa: E402
from service.evaluation.matrix import DATA, recording_named  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402

GAPS = ((1, 2), (3, 8), (9, 32), (33, 128), (129, None))  # frames unseen before the return
GROUPS = ("carried", "followed", "stranded")


def recorded_returns(name: str, cap: int) -> np.ndarray:
    """``(R, 4)`` per return: frames unseen, |e|^2 / 3, the variance given, group index."""
    rows: list[tuple[float, float, float, int]] = []
    advance = MarkerState._advance

    def recording(state: MarkerState, observed: np.ndarray, seen: np.ndarray, damping: float, rate: float) -> MarkerState:
        predicted, followed, carriers = state._prediction
        back = seen & ~state.visible & (state.unseen >= 1)
        if back.any():
            group = np.where(carriers.any(axis=1), 0, np.where(followed, 1, 2))[back]
            error = axis_mean((observed[back] - predicted[back]) ** 2)
            rows.extend(zip(state.unseen[back], error, state.prediction_var(state.unseen)[back], group))
        return advance(state, observed, seen, damping, rate)

    truth = read_labeled(DATA / recording_named(name).path)
    start = int(np.argmax((~truth.without_unlabeled().missing()).sum(axis=1)))
    end = min(truth.n_frames, start + cap) if cap else truth.n_frames
    capture, _ = capture_from_span(truth, start, end)
    MarkerState._advance = recording  # type: ignore[method-assign, assignment]
    try:
        list(CaptureLabeling(capture, LabelingOptions(second_pass=False)).windows())
    finally:
        MarkerState._advance = advance  # type: ignore[method-assign]
    return np.array(rows, dtype=float).reshape(-1, 4)


def table(name: str, returns: np.ndarray) -> None:
    """One take's table (module doc)."""
    print(f"\n{name}: {len(returns)} returns\n")
    print("| carried by | frames unseen | returns | median error mm | mean z^2 | median z^2 |")
    print("|---|---|---|---|---|---|")
    for g, group in enumerate(GROUPS):
        for low, high in GAPS:
            rows = returns[(returns[:, 3] == g) & (returns[:, 0] >= low) & (returns[:, 0] <= (high or np.inf))]
            if len(rows):
                z2 = rows[:, 1] / rows[:, 2]
                print(f"| {group} | {low}-{high or ''} | {len(rows)} | {np.sqrt(3 * np.median(rows[:, 1])):.1f} | "
                      f"{z2.mean():.2f} | {np.median(z2):.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="*", default=["ktk-basket", "numediart-rolling"], metavar="NAME",
                        help="recording names (service.evaluation.matrix.RECORDINGS)")
    parser.add_argument("--cap", type=int, default=1500, help="label at most this many frames of each take (0: all)")
    args = parser.parse_args()
    for name in args.only:
        table(name, recorded_returns(name, args.cap))


if __name__ == "__main__":
    main()
