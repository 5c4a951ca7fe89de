"""``markerflow best-view``: COSTS.csv in, CHOICES.csv out, one-line errors for bad tables."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from formulations.best_view import select_views
from service.cli.app import app

REPO = Path(__file__).resolve().parents[1]


def write_costs(path: Path, costs: np.ndarray, objects: list[str], cameras: list[str], first_frame: int = 10) -> Path:
    """Rows of ``costs[f, k, b]`` in a shuffled order (the reader must not rely on it)."""
    rows = [(first_frame + f, objects[k], cameras[b], repr(float(costs[f, k, b])))
            for f in range(costs.shape[0]) for k in range(costs.shape[1]) for b in range(costs.shape[2])]
    order = np.random.default_rng(0).permutation(len(rows))
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["frame", "object", "camera", "cost"])
        writer.writerows(rows[i] for i in order)
    return path


def read_choices(path: Path) -> list[list[str]]:
    with path.open(newline="") as f:
        return list(csv.reader(f))


def test_round_trip_through_the_command_line(tmp_path):
    costs = np.random.default_rng(3).random((25, 2, 3))
    objects, cameras = ["anna", "ben"], ["cam1", "cam2", "cam3"]
    source = write_costs(tmp_path / "costs.csv", costs, objects, cameras)
    out = tmp_path / "choices.csv"
    command = [sys.executable, "-m", "service.cli", "best-view", str(source), "--switch-cost", "0.4", "--window", "5",
               "--out", str(out)]
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "switches" in result.stdout
    rows = read_choices(out)
    assert rows[0] == ["frame", "object", "camera"]
    expected = select_views(costs, 0.4, 5)
    chosen = {(int(frame), name): camera for frame, name, camera in rows[1:]}
    assert len(rows) == 1 + 25 * 2
    assert chosen == {(10 + f, objects[k]): cameras[expected[f, k]] for f in range(25) for k in range(2)}
    assert [int(row[0]) for row in rows[1:]] == sorted(int(row[0]) for row in rows[1:])


def test_objects_with_their_own_frames_are_chosen_over_those_frames(tmp_path):
    rng = np.random.default_rng(4)
    early, late = rng.random((6, 1, 2)), rng.random((4, 1, 2))
    source = tmp_path / "costs.csv"
    write_costs(source, early, ["a"], ["x", "y"], first_frame=0)
    with source.open("a", newline="") as f:
        csv.writer(f).writerows((3 + n, "b", "xy"[c], repr(float(late[n, 0, c]))) for n in range(4) for c in range(2))
    out = tmp_path / "choices.csv"
    result = CliRunner().invoke(app, ["best-view", str(source), "--out", str(out), "--switch-cost", "0.1", "--window", "2"])
    assert result.exit_code == 0, result.output
    rows = read_choices(out)[1:]
    expected = select_views(late, 0.1, 2)[:, 0]
    assert [r for r in rows if r[1] == "b"] == [[str(3 + n), "b", "xy"[c]] for n, c in enumerate(expected)]
    assert [int(r[0]) for r in rows] == sorted(int(r[0]) for r in rows)


@pytest.mark.parametrize("text,message", [
    ("frame,object,cam,cost\n0,a,c,1\n", "header should be frame,object,camera,cost"),
    ("frame,object,camera,cost\n0,a,c,cheap\n", ":2: cost 'cheap' is not a number"),
    ("frame,object,camera,cost\n0,a,c,nan\n", "is not finite"),
    ("frame,object,camera,cost\n0.5,a,c,1\n", "frame '0.5' is not an integer"),
    ("frame,object,camera,cost\n0,a,c\n", ":2: 3 cells, expected 4"),
    ("frame,object,camera,cost\n0,a,c,1\n0,a,c,2\n", "is given twice"),
    ("frame,object,camera,cost\n0,a,c1,1\n0,a,c2,1\n1,a,c1,1\n", "no cost for frame 1, object 'a', camera 'c2'"),
    ("frame,object,camera,cost\n", "no cost rows"),
    ("", "header should be"),
])
def test_a_bad_table_is_one_line_and_exit_code_2(tmp_path, text, message):
    source = tmp_path / "costs.csv"
    source.write_text(text)
    result = CliRunner().invoke(app, ["best-view", str(source), "--out", str(tmp_path / "c.csv")])
    assert result.exit_code == 2
    assert message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "c.csv").exists()


@pytest.mark.parametrize("option,value,message", [("--switch-cost", "-1", "--switch-cost"), ("--window", "0", "--window")])
def test_bad_options_are_one_line(tmp_path, option, value, message):
    source = write_costs(tmp_path / "costs.csv", np.zeros((2, 1, 2)), ["a"], ["x", "y"])
    result = CliRunner().invoke(app, ["best-view", str(source), "--out", str(tmp_path / "c.csv"), option, value])
    assert result.exit_code == 2 and message in result.output


@pytest.mark.parametrize("data,line", [
    (b"frame,object,camera,cost\n1,a,c1,0.5\n\n1,a,c2,abc\n", 4),  # after a blank line: was :3
    (b"frame,object,camera,cost\r\n1,a,c1,0.5\r\n\r\n1,a,c2,abc\r\n", 4),  # CRLF, a blank line: was :3
    (b"frame,object,camera,cost\r\n1,a,c1,0.5\r\n1,a,c2,abc\r\n", 3),
    (b"frame,object,camera,cost\r1,a,c1,0.5\r\r1,a,c2,abc\r", 4),  # CR endings
    (b"\n\nframe,object,camera,cost\n\n1,a,c1,abc\n", 5),  # blank lines before the header too: was :2
    (b'frame,object,camera,cost\n1,"a\nb",c1,0.5\n1,a,c2,abc\n', 4),  # a line break in a quoted cell
    (b'frame,object,camera,cost\n1,a,c1,0.5\n\n1,"a\nb",c2,abc\n', 4),  # the line the row starts on
])
def test_a_bad_cell_names_the_files_own_line(tmp_path, data, line):
    source = tmp_path / "costs.csv"
    source.write_bytes(data)
    result = CliRunner().invoke(app, ["best-view", str(source), "--out", str(tmp_path / "c.csv")])
    assert result.exit_code == 2
    assert f"costs.csv:{line}: cost 'abc' is not a number" in result.output, result.output
