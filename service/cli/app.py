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
    out: Annotated[Path, typer.Option(help="Folder for the labeled C3D and the plot.")] = Path("out"),
    frames: Annotated[int, typer.Option(help="Frames of the generated scene.")] = 600,
    seed: Annotated[int, typer.Option(help="Seed of the scene and the simulated capture.")] = 0,
) -> None:
    """Label a generated scene (no data needed), print the scores, write a C3D and a plot."""
    from service.cli.demo import run_demo

    _guard(lambda: run_demo(out, frames, seed))


@app.command()
def track(
    input: Annotated[Path, typer.Argument(
        help="Capture .json (see \"Capture JSON\" in README.md), or a labeled .c3d/.trc/.csv whose first frame names the markers."
    )],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output .c3d, .trc or .csv.")],
    formulation: FormulationOption = None,
    window: WindowOption = None,
    shuffle: Annotated[bool, typer.Option(help="C3D/TRC input: shuffle each frame's points before labeling.")] = True,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object of the figures on stdout.")] = False,
) -> None:
    """Label INPUT and write the named trajectories.

    A capture JSON carries its own options; --formulation and --window override them.
    """
    from service.cli.track import run_track

    _guard(lambda: run_track(input, out, formulation, _window(window), shuffle, as_json))


@app.command("eval")
def evaluate(
    trajectories: Annotated[Path, typer.Argument(help="Labeled .c3d/.trc/.csv ground truth.")],
    scenario: Annotated[Path, typer.Option(help="Scenario TOML (see configs/scenarios/README.md).")],
    formulation: FormulationOption = None,
    window: WindowOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout.")] = False,
) -> None:
    """Run a scenario on labeled trajectories and print the scores."""
    from service.cli.evaluate import run_eval

    _guard(lambda: run_eval(trajectories, scenario, formulation, _window(window), as_json))


@app.command()
def model(
    inputs: Annotated[list[Path], typer.Argument(help="Labeled .c3d/.trc/.csv takes of one subject (a range of motion).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Subject model .json to write.")],
    centres: Annotated[Path | None, typer.Option(help="Also write the fitted joint-centre trajectories (.trc).")] = None,
) -> None:
    """Learn a subject: which markers share a rigid segment, the joints, the limb lengths."""
    from service.cli.model import run_model

    _guard(lambda: run_model(inputs, out, centres))


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


if __name__ == "__main__":
    app()
