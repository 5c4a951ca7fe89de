"""The ``markerflow`` program: the Typer app, with usage mistakes as one line like any other.

Typer shows a bad option value (``--window abc``) as a usage line, a hint and a boxed error
over six lines; scripts and users read every other mistake as one ``error:`` line on stderr
with exit code 2 (``app._guard``), so these are printed the same way.
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from types import FrameType

import typer
from rich.markup import escape
from typer.exceptions import TyperException

from service.cli.app import app
from service.cli.report import err
from service.io.formats.replace_file import watching_replaced


def main(argv: list[str] | None = None) -> int:
    """Run the command line on ``argv`` (``sys.argv[1:]`` by default); the exit code."""
    with watching_replaced() as replaced:
        try:
            code = app(args=argv, prog_name="markerflow", standalone_mode=False)
        except TyperException as error:  # a usage mistake (click's UsageError, as Typer vendors it)
            return _usage(error)
        except typer.Abort:  # Typer's name for an EOFError: no command prompts, so a reader met a file's end early
            err.print("[red]error:[/red] a file ended before its reader expected (cut short?)", highlight=False)
            return 2
        except Terminated:
            return _interrupted(143, replaced())
        if code == CTRL_C:
            return _interrupted(CTRL_C, replaced())
    return code if isinstance(code, int) else 0


def _usage(error: TyperException) -> int:
    if not error.format_message():  # no command given: the help was the answer
        return error.exit_code
    context = getattr(error, "ctx", None)
    command = context.command_path if context is not None else "markerflow"
    message = error.format_message()
    if message.startswith(("No such option: -q", "No such option: --quiet")):  # a program option, not the command's
        message += f", which goes before the command: markerflow -q {command.removeprefix('markerflow ')} ..."
    err.print(f"[red]error:[/red] {escape(message)} (see {escape(command)} --help)", highlight=False, soft_wrap=True)
    return error.exit_code


CTRL_C = 130  # Typer's exit code for a Ctrl-C, which it returns silently; no command exits so itself


class Terminated(Exception):
    """SIGTERM, raised in the main thread so that every ``finally`` runs: a half-written
    output's temporary file is removed and the file the user had stays as it was."""


def _interrupted(code: int, written: list[Path]) -> int:
    """The outputs written through ``replacing`` (every command's) are each whole, new or as
    they were; a command with several (``demo``, ``pose``, ``model --centres``) may have replaced
    some before the interrupt, so those are named rather than "no output written" said of them."""
    if written:
        done = ", ".join(str(path) for path in written)
        told = (f"interrupted: stopped before the end, after writing {done} whole; no other output written "
                "(an earlier file at their paths is untouched)")
    else:
        told = ("interrupted: stopped before the end, no output written (an earlier file at the output path is "
                "untouched)")
    err.print(escape(told), highlight=False, soft_wrap=True)
    return code


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise Terminated


def run() -> None:
    signal.signal(signal.SIGTERM, _terminate)
    sys.exit(main())
