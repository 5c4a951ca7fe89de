"""``markerflow formulations``: what can be swapped in, with parameters and defaults."""

from __future__ import annotations

from rich.table import Table

from formulations.methods.registry import describe
from service.cli.report import out


def run_formulations() -> None:
    """One table per formulation: parameter, default, meaning."""
    for description in describe():
        table = Table(title=f"{description.name}: {description.doc}", title_justify="left", show_edge=False)
        table.add_column("parameter")
        table.add_column("default")
        table.add_column("meaning")
        for parameter in description.parameters:
            table.add_row(parameter.name, repr(parameter.default), parameter.doc)
        out.print(table)
        out.print()
