"""Best view on the Pose2Sim demo: each participant's camera per frame, DP against per-frame argmax.

Four calibrated cameras (60 fps, 1088x1920 portrait) with OpenPose BODY_25B keypoints
(``../shared/data/multicam2d_pose2sim_demo``, README section 2a). Per camera, every
person becomes a box around its keypoints, the boxes are tracked (Jiang's window LP,
``service.boxes.track``), and the tracks are named after the participants by Pose2Sim's
own triangulation of them (projected into each camera; used only to say which track is
whom). A view's quality is its box area
times (1 - truncation)^2; the DP (Jiang Sec. III) runs on the relative costs
1 - q / max q with --switch-cost and --window, against the per-frame argmax of q.

Prints per trial and person: switches per 100 frames and mean quality (the chosen box's
quality over the argmax's, in %), and for all persons together. Writes to --out:
``best_view_pose2sim_<trial>.csv`` (frame,object,camera of the DP, plus the argmax's
camera and both qualities), ``best_view_pose2sim_<trial>_costs.csv`` (the COSTS.csv that
``markerflow best-view`` reproduces the choice from) and ``best_view_pose2sim_<trial>.png``
(contact sheet: per person, the chosen camera's image frame with its box, every 10th frame,
and the chosen camera over time). Goal: DP <= 1/3 of the switches at >= 95 % of the quality.

    .venv/bin/python bench/best_view_pose2sim.py [--switch-cost 1.0] [--window 30] [--out out]
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.best_view import relative_costs  # noqa: E402
from service.io.calibration import load_pose2sim_toml  # noqa: E402
from service.io.formats.trc import read_trc  # noqa: E402
from service.people.views import PeopleViews, people_views, pose2sim_world  # noqa: E402

DEMO = ROOT.parent / "shared" / "data" / "multicam2d_pose2sim_demo"
TRIALS = {
    "multiperson": ("multiperson_trial_2persons", {"P1": "Participants1-2_P1_0-100.trc", "P2": "Participants1-2_P2_0-100.trc"}),
    "balancing": ("balancing_trial_1person", {"P1": "BalancingTrial_0-100.trc"}),
}


def load(trial: str) -> PeopleViews:
    folder, trcs = TRIALS[trial]
    cameras = load_pose2sim_toml(DEMO / "calibration" / "Calib_qualisys.toml", units="mm")
    people = {name: pose2sim_world(read_trc(DEMO / folder / "pose2sim_output_3d" / trc).positions) for name, trc in trcs.items()}
    keypoints = sorted((DEMO / folder / "pose_openpose_body25b").glob("cam*_json"))
    return people_views(keypoints, cameras, people)


def switches(chosen: np.ndarray) -> np.ndarray:
    return np.count_nonzero(np.diff(chosen, axis=0), axis=0)


def write_tables(views: PeopleViews, dp: np.ndarray, argmax: np.ndarray, quality: np.ndarray, stem: Path) -> None:
    names = [camera.name for camera in views.cameras]
    picked = lambda chosen: np.take_along_axis(quality, chosen[..., None], axis=2)[..., 0]  # noqa: E731
    with stem.with_suffix(".csv").open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["frame", "object", "camera", "argmax_camera", "quality", "argmax_quality"])
        for n in range(len(dp)):
            for p, person in enumerate(views.people):
                writer.writerow([n, person, names[dp[n, p]], names[argmax[n, p]],
                                 f"{picked(dp)[n, p]:.0f}", f"{picked(argmax)[n, p]:.0f}"])
    costs = relative_costs(quality)
    with stem.parent.joinpath(stem.name + "_costs.csv").open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["frame", "object", "camera", "cost"])
        writer.writerows([n, person, name, repr(float(costs[n, p, b]))]
                         for n in range(len(dp)) for p, person in enumerate(views.people) for b, name in enumerate(names))


def contact_sheet(views: PeopleViews, dp: np.ndarray, argmax: np.ndarray, path: Path, every: int = 10) -> None:
    frames = list(range(0, len(dp), every))
    people = len(views.people)
    figure = plt.figure(figsize=(1.3 * len(frames), 3.9 * people))
    grid = figure.add_gridspec(2 * people, len(frames), height_ratios=[2.6, 1] * people, hspace=0.35)
    for p, person in enumerate(views.people):
        for i, n in enumerate(frames):
            ax, b = figure.add_subplot(grid[2 * p, i]), dp[n, p]
            width, height = views.cameras[b].image_size
            ax.add_patch(Rectangle((0, 0), width, height, facecolor="0.92", edgecolor="0.5"))
            for other in range(people):
                box = views.boxes[n, other, b]
                if np.isfinite(box).all():
                    mine = other == p
                    ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, lw=2 if mine else 1,
                                           edgecolor="tab:green" if mine else "0.6"))
            ax.set_xlim(-150, width + 150)
            ax.set_ylim(height + 50, -50)
            ax.set_aspect("equal")
            ax.axis("off")
            ax.set_title(f"{person} f{n}\n{views.cameras[b].name}", fontsize=7)
        strip = figure.add_subplot(grid[2 * p + 1, :])
        strip.step(range(len(dp)), argmax[:, p], where="mid", color="0.6", lw=1, label="per-frame argmax")
        strip.step(range(len(dp)), dp[:, p], where="mid", color="tab:green", lw=2, label="DP")
        strip.set_yticks(range(len(views.cameras)), [c.name for c in views.cameras], fontsize=7)
        strip.set_ylim(-0.5, len(views.cameras) - 0.5)
        strip.set_xlabel("frame", fontsize=7)
        strip.tick_params(labelsize=7)
        strip.legend(fontsize=6, loc="upper left")
    figure.suptitle("best view per person (green: the person's box in the chosen camera; grey: others)", fontsize=9)
    figure.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(figure)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--switch-cost", type=float, default=1.0)
    parser.add_argument("--window", type=int, default=30)
    parser.add_argument("--out", type=Path, default=ROOT / "out")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    total = {"dp": 0, "argmax": 0, "frames": 0, "dp_quality": 0.0, "argmax_quality": 0.0}
    for trial in TRIALS:
        views = load(trial)
        quality = views.quality()
        dp, argmax = views.choose(args.switch_cost, args.window), np.argmax(quality, axis=2)
        stem = args.out / f"best_view_pose2sim_{trial}"
        write_tables(views, dp, argmax, quality, stem)
        contact_sheet(views, dp, argmax, stem.with_suffix(".png"))
        n = len(dp)
        for p, person in enumerate(views.people):
            q_dp = np.take_along_axis(quality[:, p], dp[:, p, None], axis=1).sum()
            q_max = np.take_along_axis(quality[:, p], argmax[:, p, None], axis=1).sum()
            print(f"{trial} {person}: switches per 100 frames DP {100 * switches(dp)[p] / n:.1f}, "
                  f"argmax {100 * switches(argmax)[p] / n:.1f}; quality DP {100 * q_dp / q_max:.1f} % of argmax "
                  f"(tracks per camera {views.tracks})")
            total["dp"] += int(switches(dp)[p])
            total["argmax"] += int(switches(argmax)[p])
            total["frames"] += n
            total["dp_quality"] += float(q_dp)
            total["argmax_quality"] += float(q_max)
        print(f"  -> {stem}.csv, {stem}_costs.csv, {stem}.png")
    per100 = lambda key: 100 * total[key] / total["frames"]  # noqa: E731
    print(f"all persons (lambda = {args.switch_cost}, N = {args.window}): switches per 100 person-frames "
          f"DP {per100('dp'):.2f}, argmax {per100('argmax'):.2f}; mean quality DP "
          f"{100 * total['dp_quality'] / total['argmax_quality']:.1f} % of argmax")


if __name__ == "__main__":
    main()
