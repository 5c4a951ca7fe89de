"""Frames per second of ``track_boxes`` on MOT17-02 (600 frames, ~15 boxes per frame).

Input: MPNTrack's published boxes with their ids dropped. Prints the median over repeats
per formulation, and the boxes per frame.

    .venv/bin/python bench/boxes.py [--repeats 3] [--window 5] [--no-newcomer-test]
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from formulations.boxes.lifecycle import Lifecycle  # noqa: E402
from service.boxes.mot_files import read_detections, read_seqinfo  # noqa: E402
from service.boxes.track import track_boxes  # noqa: E402

SEQUENCE = Path(__file__).resolve().parents[2] / "shared" / "data" / "mot17_train_gt_and_tracker_outputs" / "MOT17-02-FRCNN"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--window", type=int, default=5)
    parser.add_argument("--no-newcomer-test", action="store_true", help="Lifecycle(returns_compete=False)")
    args = parser.parse_args()
    detections = read_detections(SEQUENCE / "trackers" / "MPNTrack.txt", read_seqinfo(SEQUENCE / "seqinfo.ini"))
    print(f"MOT17-02: {detections.n_frames} frames, {len(detections.frame) / detections.n_frames:.1f} boxes per frame, "
          f"window {args.window}")
    for formulation in ("lp-l1", "ilp", "nn-hungarian"):
        lifecycle = Lifecycle(returns_compete=not args.no_newcomer_test)
        seconds = [track_boxes(detections, formulation, window=args.window, lifecycle=lifecycle).seconds
                   for _ in range(args.repeats)]
        median = statistics.median(seconds)
        print(f"{formulation:>13}: {detections.n_frames / median:7.1f} frames/s (median of {args.repeats}: {median:.2f} s)")


if __name__ == "__main__":
    main()
