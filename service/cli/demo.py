"""``markerflow demo``: the whole pipeline on a generated scene, no data needed."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

from service.capture.document import CaptureDocument
from service.cli.output import check_writable_folder
from service.cli.report import out, print_summary, window_progress
from service.errors import InputError
from service.evaluation.cloud import evaluate
from service.evaluation.plot import plot_trajectories
from service.evaluation.scenario import Scenario
from service.evaluation.scene import generate_scene
from service.evaluation.simulated import SimulatedCapture
from service.io.formats import write_labeled
from service.io.formats.replace_file import replacing
from service.labeling.leftover_points import leftover_summary

DEMO_SCENARIO = Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0)


def run_demo(folder: Path, frames: int, seed: int) -> None:
    """Generate a walking figure, simulate a noisy capture, label it, report."""
    if frames < 2:  # a template and one frame to label
        raise InputError(f"--frames must be at least 2, got {frames}")
    if seed < 0:
        raise InputError(f"--seed must be >= 0, got {seed}")
    _make_folder(folder)
    truth = generate_scene(n_frames=frames, seed=seed)
    scenario = Scenario(**{**DEMO_SCENARIO.__dict__, "seed": seed})
    out.print(
        f"Generated scene: {truth.n_markers} markers, {truth.n_frames} frames at {truth.rate:g} Hz; "
        f"capture with {scenario.noise_mm:g} mm noise, {scenario.drop_rate:.0%} deleted samples in "
        f"{scenario.drop_burst_frames:g}-frame bursts, {scenario.ghosts_per_frame:g} ghosts per frame."
    )
    with window_progress("labeling demo scene") as progress:
        result = evaluate(truth, scenario, progress=progress)
    print_summary(result.summary(), "markerflow demo")
    c3d, png, capture = folder / "demo_labeled.c3d", folder / "demo_trajectories.png", folder / "demo_capture.json"
    write_labeled(c3d, result.result)
    plot_trajectories(result.result, png, truth=result.capture.truth)
    _write_capture(capture, result.capture)
    kept = leftover_summary(result.result)
    out.print(f"Wrote {c3d} (the points no marker took, {kept['unlabeled_points']} of them, as "
              f"{kept['unlabeled_trajectories']} unlabeled trajectories *N), {png} and the unlabeled input as {capture} "
              f"(try: {_command()} track {capture} --out {folder / 'relabeled.csv'})")


def _command() -> str:
    """``markerflow`` as this shell can run it: the name when it is on PATH, else the path of
    the one running (``make demo`` runs ``.venv/bin/markerflow``, which no PATH holds yet)."""
    running = Path(sys.argv[0])
    if shutil.which("markerflow") or running.name != "markerflow":
        return "markerflow"
    near = os.path.relpath(running)
    return str(running.resolve()) if near.startswith("..") else near


def _write_capture(path: Path, simulated: SimulatedCapture) -> None:
    """The demo's input as a capture JSON: what a user would hand ``track`` or the service.
    Written whole or not at all, as the other outputs: a Ctrl-C left a cut JSON."""
    with replacing(path) as temp:
        temp.write_text(CaptureDocument.of(simulated.capture()).model_dump_json(), encoding="utf-8")


def _make_folder(folder: Path) -> None:
    """Create the output folder before the work, so a bad ``--out`` fails at once."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # e.g. a file of that name, or no permission
        raise InputError(f"{folder}: cannot create the output folder ({exc.strerror})") from None
    check_writable_folder(folder)
