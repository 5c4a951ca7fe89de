"""Where a real take's labels are won and lost: each stage of `track` scored against the file's labels.

`markerflow track` labels a take in stages (``CaptureLabeling.label``): the window pass; on a
doubtful take a second pass and, merged group by group, a frame-by-frame reading
(``refine``, docs/track.md); the take-wide repairs (exchanges, rotations of three markers,
hand-overs given back); then fill, calibration and shape doubt, which change no label.
`bench/real_takes.py` scores only the end. Here each take is relabeled as there (from S, the
first frame with the most markers labeled, markers absent at S left out) and the labels after
each stage are scored over the marker-frames the labeling can reach (markers named at S, their
points present, frame S excluded: the user gave it):

- windows: the first pass's windows as they are;
- refined: after the second pass and the frame-by-frame reading (what was kept and taken is
  in the last columns: the pass kept, markers taken from the other pass, markers taken from
  the frame-by-frame reading; "-" where it did not run);
- repaired: with the take-wide exchanges/rotations and hand-overs (how many of each);
- worst: the markers that lose the most marker-frames at the end (wrong + missing).

On real 03_rolling (2026-12-03, 1,743 frames from 562): windows 79.92 %, refined 88.98 %,
repaired 91.10 %. A stage that costs a take shows as a drop between two columns.

    .venv/bin/python bench/real_stages.py [--only NAME ...] [--cap FRAMES]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from service.capture.capture import LabelingOptions  # noqa: E402
from service.capture.from_recording import capture_from_span  # noqa: E402
from service.evaluation.matrix import DATA, RECORDINGS  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.io.recording import LabeledTrajectories, Recording  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402


def reached(truth: Recording, start: int, labels: LabeledTrajectories) -> tuple[np.ndarray, np.ndarray]:
    """``(F, N)`` right labels and present marker-frames of ``labels`` (frame ``start`` on, the
    labeled first frame excluded), per marker of ``labels`` in its order."""
    rows = slice(start, start + labels.n_frames)
    own = truth.positions[rows][:, [truth.names.index(n) for n in labels.names]]
    present = np.isfinite(own).all(axis=2)
    present[0] = False
    right = present & (np.linalg.norm(labels.positions - own, axis=2) <= 1e-3)
    return right, present


def stage_row(name: str, truth: Recording, cap: int) -> str:
    """One take's table row (module doc)."""
    labeled = truth.without_unlabeled()
    start = int(np.argmax((~labeled.missing()).sum(axis=1)))
    end = min(truth.n_frames, start + cap) if cap else truth.n_frames
    capture, _ = capture_from_span(truth, start, end)
    labeling = CaptureLabeling(capture, LabelingOptions())
    first = list(labeling.windows())
    refined = labeling.refine(list(first))
    assert refined is not None  # only a stop abandons it
    stages = [labeling.assembled(first, repaired=False), labeling.assembled(refined, repaired=False),
              labeling.assembled(refined)]  # last: the repairs it gives back are the ones reported below
    scored = [reached(labeled, start, labels) for labels in stages]
    cells = [f"{100 * right[present].mean():.2f} %" for right, present in scored]
    right, present = scored[-1]
    lost = (present & ~right).sum(axis=0)
    worst = ", ".join(f"{stages[-1].names[m]} {lost[m]}" for m in np.argsort(-lost)[:3] if lost[m])
    choice, rival = labeling.choice, labeling.rival
    handled = (f"{len(labeling.exchanges)} / {len(labeling.handovers)}",
               "-" if choice is None or choice.second_doubtful is None else f"{choice.kept} ({choice.taken_from_other})",
               "-" if rival is None else str(rival.markers))
    return f"| {name} | {start} | {end - start} | {len(capture.names)} | " + " | ".join([*cells, *handled, worst or "-"]) + " |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="*", choices=[r.name for r in RECORDINGS], metavar="NAME",
                        help="recording names (service.evaluation.matrix.RECORDINGS)")
    parser.add_argument("--cap", type=int, default=0, help="label at most this many frames of each take")
    args = parser.parse_args()
    print("| take | start | frames | markers named | windows | refined | repaired | exchanges / hand-overs | "
          "pass kept (markers from other) | from frame-by-frame | worst (marker-frames lost) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for recording in RECORDINGS:
        if not args.only or recording.name in args.only:
            print(stage_row(recording.name, read_labeled(DATA / recording.path), args.cap), flush=True)


if __name__ == "__main__":
    main()
