"""The ``markerflow`` command line."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from service.errors import InputError

app = typer.Typer(add_completion=False, no_args_is_help=True, help="Name every marker in every frame.")
err = Console(stderr=True)
# Help texts are Rich markup: a literal "[formulation]" must be written escaped, or it vanishes.
FORMULATION_TABLE = escape("[formulation]")

FormulationOption = Annotated[str | None, typer.Option(
    "--formulation", "-f",
    help=f"Formulation name (see `markerflow formulations`) or a TOML file with a {FORMULATION_TABLE} table.",
)]
WindowOption = Annotated[int | None, typer.Option("--window", "-w", help="Frames per window, template included.")]


@app.callback()
def main(
    quiet: Annotated[bool, typer.Option(
        "--quiet", "-q", help="No progress on stderr (before the command: markerflow -q track ...); results still print.",
    )] = False,
) -> None:
    """Name every marker in every frame."""
    from service.cli import report

    report.quiet = quiet


@app.command()
def demo(
    out: Annotated[Path, typer.Option(
        help="Folder for the labeled C3D, the plot and the unlabeled input as a capture JSON.",
    )] = Path("out"),
    frames: Annotated[int, typer.Option(help="Frames of the generated scene.")] = 600,
    seed: Annotated[int, typer.Option(help="Seed of the scene and the simulated capture.")] = 0,
) -> None:
    """Label a generated scene (no data needed), print the scores, write a C3D and a plot."""
    from service.cli.demo import run_demo

    _guard(lambda: run_demo(out, frames, seed))


@app.command()
def track(
    input: Annotated[Path, typer.Argument(
        help="Capture .json (see \"Capture JSON\" in README.md), or a labeled .c3d/.trc/.csv whose first frame "
        "(or --start frame) names the markers."
    )],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output .c3d, .trc or .csv.")],
    formulation: FormulationOption = None,
    window: WindowOption = None,
    shuffle: Annotated[bool, typer.Option(help="C3D/TRC input: shuffle each frame's points before labeling.")] = True,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object of the figures on stdout.")] = False,
    subject: Annotated[Path | None, typer.Option(
        "--model", help="Subject model .json (markerflow model): no labeled frame; INPUT's labels are discarded "
        "(see --keep-labels).",
    )] = None,
    keep_labels: Annotated[bool, typer.Option(
        "--keep-labels", help="With --model: keep INPUT's labels at the --start frame (a partly labeled frame); "
        "the model names only the markers absent there.",
    )] = False,
    start: Annotated[int | None, typer.Option(
        help="First frame to label (default 0). A recording starts from its own labels there (markers absent there "
        "stay unlabeled); with --model, from the model's identification (or its labels there, --keep-labels). "
        "A .c3d output of a .c3d input keeps the frames outside "
        "--start/--end, unlabeled; any other output holds the labeled frames only, numbered as in the input.",
    )] = None,
    end: Annotated[int | None, typer.Option(help="Label frames before this one (default: to the last frame).")] = None,
    second_pass: Annotated[bool | None, typer.Option(
        "--second-pass/--one-pass", help="3D points, no --model: label again from the distance spreads the first "
        "labeling measured, keep the labeling whose rigid pairs agree better with the start frame, and on a "
        "doubtful take read it frame by frame too, taking the markers that reading labels better (up to "
        "three times the time). Default: on, "
        "or a capture document's own second_pass.", show_default=False,
    )] = None,
    mht_reading: Annotated[bool, typer.Option(
        "--mht-reading", help="Where the frame-by-frame reading runs, read the take by mht as well and take the "
        "markers that reading labels better (about twice the time of a doubtful take).",
    )] = False,
) -> None:
    """Label INPUT and write the named trajectories.

    A capture JSON carries its own options; --formulation and --window override them.
    """
    from service.cli.track import run_track

    _guard(lambda: run_track(
        input, out, formulation, _window(window), shuffle, as_json, subject, start, end, second_pass, keep_labels, mht_reading,
    ))


@app.command("eval")
def evaluate(
    trajectories: Annotated[Path, typer.Argument(help="Labeled .c3d/.trc/.csv ground truth.")],
    scenario: Annotated[Path, typer.Option(help="Scenario TOML (see configs/scenarios/README.md).")],
    formulation: FormulationOption = None,
    window: WindowOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout.")] = False,
    subject: Annotated[Path | None, typer.Option(
        "--model", help="Subject model .json: the labeler gets no labeled frame (scenario first_frame = \"model\").",
    )] = None,
) -> None:
    """Run a scenario on labeled trajectories and print the scores."""
    from service.cli.evaluate import run_eval

    _guard(lambda: run_eval(trajectories, scenario, formulation, _window(window), as_json, subject))


@app.command()
def model(
    inputs: Annotated[list[Path], typer.Argument(help="Labeled .c3d/.trc/.csv takes of one subject (a range of motion).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Subject model .json to write.")],
    centres: Annotated[Path | None, typer.Option(
        help="Also write the fitted joint-centre trajectories: .trc or .c3d in the first take's unit, .csv in mm.",
    )] = None,
    markerset: Annotated[str | None, typer.Option(
        help="Marker-set template: a name in configs/markersets (cmu-41, plug-in-gait, gait2354, rajagopal) or a .toml; "
        "then a static take is enough.",
    )] = None,
    start: Annotated[int, typer.Option(help="First frame of each take to learn from, counted from 0.")] = 0,
    end: Annotated[int | None, typer.Option(help="Learn from frames before this one (default: to the end).")] = None,
) -> None:
    """Learn a subject: which markers share a rigid segment, the joints, the limb lengths."""
    from service.cli.model import run_model

    _guard(lambda: run_model(inputs, out, centres, markerset, start, end))


@app.command()
def pose(
    input: Annotated[Path, typer.Argument(
        help="Folder of per-camera OpenPose BODY_25B JSON folders (Pose2Sim layout: camNN_json), or of per-camera image folders.",
    )],
    calibration: Annotated[Path, typer.Option(help="Calibration: Pose2Sim .toml, caliscope .toml or markerflow .json.")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", help="Joint trajectories .trc (calibration frame and units); a .png overlay beside it.",
    )],
    model: Annotated[Path | None, typer.Option(
        "--model", help="Subject model .json (markerflow model) to build the body from; default: a human sized to the take.",
    )] = None,
    particles: Annotated[int, typer.Option(help="N: particles per layer.")] = 300,
    layers: Annotated[int, typer.Option(help="M: annealing layers per frame.")] = 10,
    rate: Annotated[float, typer.Option(help="Frames per second of the video (OpenPose JSON does not say).")] = 60.0,
    seed: Annotated[int, typer.Option(help="Seed of the particle filter.")] = 0,
    refine: Annotated[bool, typer.Option(
        help="Polish each keypoint fit by bounded least squares after the particle filter (--no-refine: the APF alone).",
    )] = True,
) -> None:
    """Fit an articulated body to every frame by annealed particle filtering (Davison, Deutscher & Reid 2001)."""
    from service.cli.pose import run_pose

    _guard(lambda: run_pose(input, calibration, out, model, particles, layers, rate, seed, refine))


@app.command("best-view")
def best_view(
    costs: Annotated[Path, typer.Argument(help="COSTS.csv: frame,object,camera,cost (lower is better), one row per triple.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="CHOICES.csv to write: frame,object,camera.")],
    switch_cost: Annotated[float, typer.Option(help="lambda: the price of one camera switch, in cost units.")] = 1.0,
    window: Annotated[int, typer.Option(help="N: frames per sliding window, the current one included.")] = 30,
) -> None:
    """Pick each object's camera per frame by Jiang's sliding-window DP (quality plus a price per switch)."""
    from service.cli.best_view import run_best_view

    _guard(lambda: run_best_view(costs, out, switch_cost, window))


@app.command()
def boxes(
    detections: Annotated[Path, typer.Argument(help="MOTChallenge det.txt (frame, id, left, top, width, height, conf, ...).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="MOTChallenge result file to write.")],
    formulation: Annotated[str, typer.Option(
        "--formulation", "-f", help=f"lp-l1, ilp, nn-hungarian, ... or a TOML with a {FORMULATION_TABLE} table.",
    )] = "lp-l1",
    seqinfo: Annotated[Path | None, typer.Option(help="seqinfo.ini: sequence length and image size.")] = None,
    images: Annotated[Path | None, typer.Option(help="Folder of frames (000001.jpg, ...): adds 64-bin grey histograms.")] = None,
    window: Annotated[int, typer.Option("--window", "-w", help="Frames per window, template included.")] = 5,
    newcomer_test: Annotated[bool, typer.Option(
        "--newcomer-test/--no-newcomer-test",
        help="Weigh boxes a lost object takes back against a new person (off: the window's costs alone decide).",
    )] = True,
    occluded: Annotated[bool, typer.Option(
        "--occluded/--no-occluded",
        help="Also write each object's boxes while it was held occluded between two sightings (confidence 0).",
    )] = True,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object of the figures on stdout.")] = False,
) -> None:
    """Track the boxes of one camera (Jiang's window LP) and write MOTChallenge results."""
    from service.cli.boxes import run_boxes

    _guard(lambda: run_boxes(
        detections, out, formulation, seqinfo, images, _window(window) or 5, as_json, newcomer_test, occluded,
    ))


@app.command("mot-eval")
def mot_eval(
    result: Annotated[Path, typer.Argument(help="MOTChallenge result file.")],
    gt: Annotated[Path, typer.Argument(help="MOTChallenge gt.txt.")],
    seqinfo: Annotated[Path | None, typer.Option(help="seqinfo.ini (default: the one beside the gt folder, if any).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout.")] = False,
) -> None:
    """Score a MOTChallenge result with TrackEval: HOTA, MOTA, IDF1, ID switches."""
    from service.cli.mot_eval import run_mot_eval

    _guard(lambda: run_mot_eval(result, gt, seqinfo, as_json))


@app.command("formulations")
def list_formulations() -> None:
    """List the window formulations with their parameters and defaults."""
    from service.cli.formulations import run_formulations

    _guard(run_formulations)


@app.command()
def integrality(
    formulation: Annotated[str, typer.Option(
        "--formulation", "-f", help=f"Name or TOML with a {FORMULATION_TABLE} table.",
    )] = "lp-l1",
    corpus: Annotated[Path | None, typer.Option(help="Corpus folder (default: the repo's tests/fixtures/integrality).")] = None,
) -> None:
    """Integral windows, gaps and agreement with the ILP optimum on the window corpus."""
    from service.cli.integrality import run_integrality

    _guard(lambda: run_integrality(formulation, corpus))


@app.command()
def serve(
    host: Annotated[str | None, typer.Option(help="Address to bind (default 127.0.0.1; another needs tokens).")] = None,
    port: Annotated[int | None, typer.Option(help="Port (default 8000; 0 picks a free one).")] = None,
    db: Annotated[str | None, typer.Option(
        help="Job store: a SQLite file path, or an SQLAlchemy URL (default sqlite:///markerflow.db in the working folder)."
    )] = None,
    dask: Annotated[str | None, typer.Option(help="Dask scheduler address (tcp://...): run jobs there.")] = None,
    config: Annotated[Path | None, typer.Option(help="Service TOML (see configs/service.toml).")] = None,
) -> None:
    """Run the HTTP service: submit captures as jobs, follow them, fetch labeled results."""
    from service.cli.serve import run_serve

    _guard(lambda: run_serve(host, port, db, dask, config))


def _window(window: int | None) -> int | None:
    """Checked here, inside ``_guard``, so the message names the option, not a scenario key."""
    if window is not None and window < 2:
        raise InputError(f"--window must be at least 2 frames (a template and one new frame), got {window}")
    return window


def _guard(action) -> None:
    """A user mistake is one line on stderr and exit code 2, never a traceback."""
    try:
        action()
    except InputError as error:
        # escape: a path like `take[1].c3d` is text, not Rich markup; soft_wrap: one
        # line however narrow the terminal, so scripts can read it.
        err.print(f"[red]error:[/red] {escape(str(error))}", highlight=False, soft_wrap=True)
        raise typer.Exit(2) from None

