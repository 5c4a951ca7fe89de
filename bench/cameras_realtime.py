"""Milliseconds per frame for 41 markers seen by 4 cameras, from 2D detections to labeled 3D.

CMU 85_02 placed in the real Pose2Sim 4-camera rig through the issue's scenario
(``configs/scenarios/cmu-85-02-pose2sim-cameras.toml``: 0.5 px noise, 3 px blob merging,
10 % occlusion in 15-frame bursts, 2 clutter points per camera). Prints medians over runs.

Both associations are timed through ``CaptureLabeling``, from detections to labeled 3D (the
total). For ``joint-3d`` the matching alone (epipolar gating, triangulation, growth and merging
of the cross-camera points, plus their detection resources) is timed beside it, in the blocks
of frames the labeling matches in (``service.labeling.joint_3d``) and one frame at a time;
labeling is the total less the matching in blocks. Goal: <= 4 ms per frame in total.

    .venv/bin/python bench/cameras_realtime.py [--runs 5] [--frames 0] [--association joint-3d|per-camera]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.cameras.camera import Camera  # noqa: E402
from formulations.cameras.rig import Rig  # noqa: E402
from service.capture.capture import Capture, LabelingOptions  # noqa: E402
from service.evaluation.scenario import Scenario  # noqa: E402
from service.evaluation.simulate_cameras import CameraCapture, place_in_volume, simulate_cameras  # noqa: E402
from service.io.calibration import load_calibration  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402
from service.io.recording import Recording  # noqa: E402
from service.labeling.capture_labeling import CaptureLabeling  # noqa: E402
from service.labeling.joint_3d import cross_camera_cloud  # noqa: E402

SCENARIO = ROOT / "configs" / "scenarios" / "cmu-85-02-pose2sim-cameras.toml"
RECORDING = ROOT.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def simulate(frames: int) -> tuple[list[Camera], CameraCapture]:
    scenario = Scenario.from_toml(SCENARIO)
    cameras = load_calibration(Path(scenario.calibration), units="mm")
    rig = Rig.of(cameras)
    truth = read_labeled(RECORDING)
    positions = truth.positions[: frames or truth.n_frames]
    capture = simulate_cameras(
        Recording(truth.names, place_in_volume(positions, rig, up_axis=scenario.up_axis), truth.rate), rig,
        pixel_noise=scenario.pixel_noise, merge_radius_px=scenario.merge_radius_px,
        occlusion_rate=scenario.occlusion_rate, occlusion_burst_frames=scenario.occlusion_burst_frames,
        clutter_per_camera=scenario.clutter_per_camera, seed=scenario.seed,
    )
    return cameras, capture


def matching(cameras: list[Camera], simulated: CameraCapture, block_frames: int) -> float:
    """Seconds per frame to match every frame across cameras, with its resources."""
    n = len(simulated.detections)
    start = time.perf_counter()
    cloud, _ = cross_camera_cloud(cameras, simulated.detections, simulated.truth.rate, block_frames=block_frames)
    for f in range(n):
        cloud.resources[f]  # matches the frame's block, then builds its resource rows
    return (time.perf_counter() - start) / n


def total(cameras: list[Camera], simulated: CameraCapture, association: str) -> float:
    """Seconds per frame from the detections to the labeled trajectories."""
    first = simulated.first_frame
    capture = Capture(list(first.names), first.positions[0], first.rate, cameras=cameras, detections=simulated.detections)
    start = time.perf_counter()
    CaptureLabeling(capture, LabelingOptions(association=association)).label()
    return (time.perf_counter() - start) / len(simulated.detections)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--frames", type=int, default=0, help="0: the whole recording")
    parser.add_argument("--association", choices=("joint-3d", "per-camera"), default="joint-3d")
    args = parser.parse_args()
    cameras, capture = simulate(args.frames)
    n_markers, n_frames = capture.marker_detection.shape[2], len(capture.detections)
    print(f"85_02: {n_frames} frames, {n_markers} markers, {len(cameras)} cameras, {args.association}")
    ms = {"total": 1000 * float(np.median([total(cameras, capture, args.association) for _ in range(args.runs)]))}
    if args.association == "joint-3d":
        for block in (20, 1):
            ms[f"matching {block}"] = 1000 * float(np.median([matching(cameras, capture, block) for _ in range(args.runs)]))
        print(f"matching in blocks of 20 frames {ms['matching 20']:.2f}, one frame at a time {ms['matching 1']:.2f}; "
              f"labeling {ms['total'] - ms['matching 20']:.2f} ms/frame")
    print(f"total {ms['total']:.2f} ms/frame")
    print(f"(medians of {args.runs} runs; real time at 120 Hz is 8.33 ms per frame, the goal 4 ms)")


if __name__ == "__main__":
    main()
