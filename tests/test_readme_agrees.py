"""README.md's examples say what the code does: the capture JSON example is a document
``markerflow track`` labels, and the API comment names real fields."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

from typer.testing import CliRunner

from formulations.window.solution import WindowSolution
from service.cli.app import app

README = Path(__file__).resolve().parents[1] / "README.md"


def _block(heading: str, language: str) -> str:
    """The first ``language`` code block after ``heading`` in the README."""
    section = README.read_text(encoding="utf-8").split(heading, 1)[1]
    found = re.search(rf"```{language}\n(.*?)```", section, re.S)
    assert found is not None, f"no {language} block after {heading}"
    return found.group(1)


def test_the_capture_json_example_is_a_document_track_labels(tmp_path: Path) -> None:
    document, out = tmp_path / "capture.json", tmp_path / "out.csv"
    document.write_text(_block("## Capture JSON", "json"), encoding="utf-8")
    result = CliRunner().invoke(app, ["-q", "track", str(document), "--out", str(out)])
    assert result.exit_code == 0, result.stderr
    rows = out.read_text().splitlines()
    assert len(rows) == 3  # the header, the labeled frame 0 and frame 1
    assert rows[1].split(",")[2] != ""  # LFHD_x in frame 0: triangulated, not missing


def test_the_window_solution_comment_names_its_fields() -> None:
    found = re.search(r"# a WindowSolution: (.*)", README.read_text(encoding="utf-8"))
    assert found is not None
    named = [name.strip() for name in found.group(1).split(",")]
    fields = {field.name for field in dataclasses.fields(WindowSolution)}
    assert named and all(name in fields or isinstance(getattr(WindowSolution, name, None), property) for name in named)
