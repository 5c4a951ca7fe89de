"""README.md's examples say what the code does: the capture JSON example is a document
``markerflow track`` labels, and the API comment names real fields."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

from typer.testing import CliRunner

from formulations.window.solution import WindowSolution
from service.cli.app import app

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"


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


def test_the_library_example_runs_as_written(tmp_path: Path, monkeypatch, capsys) -> None:
    """The Quick start's Python block, run on 30 frames of CMU 85_02 with a ghost per frame: it
    labels, prints the warnings and writes the C3D it says it writes."""
    import numpy as np

    from service.io.formats import read_labeled

    take = read_labeled(REPO.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d")
    rng = np.random.default_rng(0)
    frames = [take.positions[0]] + [np.vstack([p, p[:1] + rng.normal(0, 200, (1, 3))]) for p in take.positions[1:30]]
    monkeypatch.chdir(tmp_path)
    scope = {"names": list(take.names), "first_frame": take.positions[0], "frames": frames}
    exec(_block("## Quick start", "python"), scope)  # noqa: S102  # the README's own code
    written = read_labeled(tmp_path / "take_labeled.c3d")
    assert written.n_frames == 30 and written.names[: len(take.names)] == list(take.names)
    assert np.nanmax(np.abs(written.positions[:, : len(take.names)] - take.positions[:30])) < 1e-3
