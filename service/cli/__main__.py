"""``python -m service.cli``: the same command line as ``markerflow``."""

from service.cli.launch import run

run()
