"""The box-tracking table of issue 16: HOTA, MOTA, IDF1, ID switches, frames/s.

Per sequence, ``markerflow boxes`` with lp-l1, ilp and nn-hungarian (same costs, windows,
births and deaths), and for reference published tracker outputs scored as they are:

- TUD-Campus, TUD-Stadtmitte: SORT's published Faster R-CNN detections as input; ground
  truth from the ``motmetrics`` package (``motmetrics/data/TUD-*/gt.txt``), with the
  tracker output that ships beside it (``test.txt``) as the reference row.
- MOT17-02/05/09: MPNTrack's published output with its ids dropped as detections
  (MOTChallenge's public det.txt is not in ../shared/data); MPNTrack and Lif_T as they are.

The cost constants were chosen on TUD-Campus and MOT17-02; the other three are held out.

Arcs are priced by Jiang's weighted costs, or with ``--likelihood`` as negative
log-likelihoods (``formulations.boxes.likelihood``), the same for every formulation.

By default a chain a lost object took after a miss is weighed as its return against a
newcomer (``Lifecycle(returns_compete=True)``, ``formulations.boxes.returns``), for every
formulation; ``--no-newcomer-test`` leaves it to the window's costs.

By default each object's boxes while it was held occluded between two sightings are written
too (``BoxTracks.with_occluded``), for every formulation; ``--no-occluded`` writes only the
boxes taken.

    .venv/bin/python bench/mot_table.py [--window 5] [--formulations lp-l1,ilp,nn-hungarian] [--likelihood]
        [--no-newcomer-test] [--no-occluded]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import motmetrics  # noqa: E402

from formulations.boxes.lifecycle import Lifecycle  # noqa: E402
from service.boxes.mot_files import read_detections, read_seqinfo, write_tracks  # noqa: E402
from service.boxes.scores import mot_scores  # noqa: E402
from service.boxes.track import track_boxes  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
MOTMETRICS = Path(motmetrics.__file__).parent / "data"


def sequences() -> list[tuple[str, Path, Path, Path | None, dict[str, Path]]]:
    """(name, detections, gt, seqinfo, published outputs) per sequence."""
    rows: list[tuple[str, Path, Path, Path | None, dict[str, Path]]] = []
    for name in ("TUD-Campus", "TUD-Stadtmitte"):
        rows.append((name, DATA / "mot15_sort_frcnn_detections" / name / "det.txt", MOTMETRICS / name / "gt.txt", None,
                     {"motmetrics test.txt": MOTMETRICS / name / "test.txt"}))
    for number in ("02", "05", "09"):
        base = DATA / "mot17_train_gt_and_tracker_outputs" / f"MOT17-{number}-FRCNN"
        trackers = {t: base / "trackers" / f"{t}.txt" for t in ("MPNTrack", "Lif_T")}
        rows.append((f"MOT17-{number}", trackers["MPNTrack"], base / "gt" / "gt.txt", base / "seqinfo.ini", trackers))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--window", type=int, default=5)
    parser.add_argument("--formulations", default="lp-l1,ilp,nn-hungarian")
    parser.add_argument("--likelihood", action="store_true", help="negative log-likelihood arc costs")
    parser.add_argument("--no-newcomer-test", action="store_true",
                        help="Lifecycle(returns_compete=False): the window's costs alone decide a lost object's return")
    parser.add_argument("--no-occluded", action="store_true",
                        help="write only the boxes taken, not each object's boxes while held occluded")
    args = parser.parse_args()
    print("| sequence | tracker | HOTA | MOTA | IDF1 | ID sw. | frames/s |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for name, det, gt, seqinfo, published in sequences():
            detections = read_detections(det, read_seqinfo(seqinfo) if seqinfo else None)
            for formulation in args.formulations.split(","):
                run = track_boxes(detections, formulation, window=args.window, likelihood=args.likelihood,
                                  lifecycle=Lifecycle(returns_compete=not args.no_newcomer_test))
                result = Path(folder) / f"{name}-{formulation}.txt"
                write_tracks(result, run.tracks if args.no_occluded else run.tracks.with_occluded())
                s = mot_scores(result, gt, seqinfo)
                fps = detections.n_frames / run.seconds
                print(f"| {name} | {formulation} | {s.hota:.3f} | {s.mota:.3f} | {s.idf1:.3f} | {s.id_switches} | {fps:.0f} |",
                      flush=True)
            for tracker, path in published.items():
                s = mot_scores(path, gt, seqinfo)
                print(f"| {name} | {tracker} (published) | {s.hota:.3f} | {s.mota:.3f} | {s.idf1:.3f} | {s.id_switches} | |")


if __name__ == "__main__":
    main()
