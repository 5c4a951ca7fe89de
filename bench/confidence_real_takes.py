"""Is the reported confidence calibrated on real takes? Each labeled recording relabeled, raw and calibrated p scored.

Each take of ``service.evaluation.matrix.RECORDINGS`` is relabeled as ``bench/real_takes.py``
has `markerflow track` do it (from the first frame with the most markers labeled, whole
take, default options), in the library so that the raw confidences can be read
(``CaptureLabeling.result(..., calibrated=False)``). A label is right where the point it
took is the file's own point for that marker; labels where the file has none are left out
(the file does not say). Printed per take and pooled: labels, wrong, the doubtful share and
recall (the same labels raw and calibrated: the map is monotone), and the Brier score and
the expected calibration error of the raw and of the calibrated p
(``formulations.confidence.calibration``), and of the confidence a result reports
(calibrated, then lone labels and shape breaks capped: ``service.labeling.reported``,
``service.labeling.shape_doubt``). The file's own labels are no truth where they are
corrupt (CMU 135_02's left foot from frame 4486, docs/measured.md).

    .venv/bin/python bench/confidence_real_takes.py [--only NAME ...]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from confidence_calibration import scores  # noqa: E402

from formulations.confidence.calibration import LABEL_CALIBRATION  # noqa: E402
from service.capture.capture import LabelingOptions  # noqa: E402
from service.capture.from_recording import capture_from_span  # noqa: E402
from service.evaluation.matrix import DATA, RECORDINGS  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402
from service.labeling.stats import DOUBTFUL_BELOW, REPORTED_DOUBTFUL_BELOW  # noqa: E402


def take_labels(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(L,)`` raw and reported confidence and right of every label of the relabeled take (frame 0 of the span is given)."""
    recording = read_labeled(path)
    truth = recording.without_unlabeled()
    start = int(np.argmax((~truth.missing()).sum(axis=1)))
    capture, _ = capture_from_span(recording, start)
    labeling = CaptureLabeling(capture, LabelingOptions())
    outcomes = labeling.refine(list(labeling.windows()))
    assert outcomes is not None  # no stop was asked for
    result = labeling.result(outcomes, calibrated=False)
    reported = labeling.result(outcomes).confidence
    own = truth.positions[start : start + result.n_frames][:, [truth.names.index(n) for n in result.names]]
    labeled = np.isfinite(result.positions).all(axis=2) & np.isfinite(own).all(axis=2)
    labeled[0] = False
    right = np.linalg.norm(result.positions - own, axis=2) < 1e-3
    return result.confidence[labeled], reported[labeled], right[labeled]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--only", nargs="+", help="recording names (as in the accuracy matrix)")
    args = parser.parse_args()
    pooled: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for recording in RECORDINGS:
        if args.only and recording.name not in args.only:
            continue
        labels = take_labels(DATA / recording.path)
        pooled.append(labels)
        report(recording.name, *labels)
    report("all", *(np.concatenate(part) for part in zip(*pooled)))


def report(name: str, raw: np.ndarray, reported: np.ndarray, right: np.ndarray) -> None:
    print(f"{name:18s} {len(raw):7d} labels, {1 - right.mean():6.2%} wrong")
    print(f"{'':18s} raw        {scores(raw, right, DOUBTFUL_BELOW)}")
    print(f"{'':18s} calibrated {scores(LABEL_CALIBRATION(raw), right, REPORTED_DOUBTFUL_BELOW)}")
    print(f"{'':18s} reported   {scores(reported, right, REPORTED_DOUBTFUL_BELOW)}", flush=True)


if __name__ == "__main__":
    main()
