"""The ``markerflow`` console script: the command line imported under a Ctrl-C guard.

Importing it (numpy, scipy, HiGHS, Typer, ...) takes about a second, before ``entry`` can
catch anything: a Ctrl-C then printed a Python traceback where every later one is a line.
"""

from __future__ import annotations

import sys

CTRL_C = 130  # as ``entry.CTRL_C``, which is not imported yet


def run() -> None:
    try:
        from service.cli.entry import run as run_command_line
    except KeyboardInterrupt:
        sys.stderr.write("interrupted: stopped before the end, no output written\n")
        raise SystemExit(CTRL_C) from None
    run_command_line()
