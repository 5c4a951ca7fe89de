"""``markerflow integrality``: how often a formulation's relaxation is integral on the corpus."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

from service.capture.formulation_spec import formulation_from_spec
from service.cli.report import out, window_progress
from service.evaluation.integrality import corpus_figures

DEFAULT_CORPUS = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "integrality"


def run_integrality(formulation: str, corpus: Path | None) -> None:
    """One row per corpus: windows, integral %, gaps, rounded == optimum %, time."""
    chosen = formulation_from_spec(formulation)
    table = Table(title=f"integrality of {formulation}", title_justify="left")
    table.add_column("corpus", no_wrap=True)
    for column in ("windows", "integral", "gap p50", "gap max", "=ILP opt", "ms/win"):
        table.add_column(column, justify="right", no_wrap=True)
    with window_progress(f"integrality of {formulation}") as progress:
        figures = corpus_figures(corpus or DEFAULT_CORPUS, chosen, progress)
    for f in figures:
        table.add_row(f.corpus, str(f.windows), f"{f.integral_fraction:.0%}", f"{f.gap_median:.1e}",
                      f"{f.gap_max:.1e}", f"{f.optimal_fraction:.0%}", f"{1000 * f.seconds_median:.1f}")
    out.print(table)
