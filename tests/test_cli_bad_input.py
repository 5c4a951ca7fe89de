"""Bad input to the command line: one line on stderr, exit code 2, never a traceback."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from test_cli import CMU, assert_input_error, cmu_points, run_cli, write_c3d, write_scenario


def truncated_c3d(tmp: Path) -> Path:
    data = CMU.read_bytes()
    (tmp / "half.c3d").write_bytes(data[: len(data) // 2])
    return tmp / "half.c3d"


def nan_first_frame_c3d(tmp: Path) -> Path:
    labels, points = cmu_points(60)
    points[:, 3, 0] = np.nan  # Male:RBWT
    return write_c3d(tmp / "gap.c3d", labels, points)


def all_missing_c3d(tmp: Path) -> Path:
    labels, points = cmu_points(60)
    return write_c3d(tmp / "none.c3d", labels, np.full_like(points, np.nan))


def blank_labels_c3d(tmp: Path) -> Path:
    _, points = cmu_points(60)
    return write_c3d(tmp / "blank.c3d", [""] * 3, points[:, :3])


def no_points_c3d(tmp: Path) -> Path:
    # ezc3d refuses to write points without labels, but it writes a file with no points.
    return write_c3d(tmp / "empty.c3d", [], np.zeros((3, 0, 60)))


def wrong_suffix(tmp: Path) -> Path:
    """A real C3D under a suffix no reader takes."""
    (tmp / "markers.xyz").write_bytes(CMU.read_bytes())
    return tmp / "markers.xyz"


def existing_file(tmp: Path) -> Path:
    (tmp / "taken").write_text("not a folder", encoding="utf-8")
    return tmp / "taken"


def folder(tmp: Path, name: str) -> Path:
    (tmp / name).mkdir()
    return tmp / name


def copied(tmp: Path, name: str = "take.c3d") -> Path:
    """A copy of a real take (its bytes) the output must not replace."""
    (tmp / name).write_bytes(CMU.read_bytes())
    return tmp / name


def track(tmp: Path, source: Path, *more: str) -> list[str | Path]:
    return ["track", source, "--out", tmp / "x.c3d", *more]


def evaluate(tmp: Path, source: Path, *more: str) -> list[str | Path]:
    return ["eval", source, "--scenario", write_scenario(tmp / "s.toml", 40), *more]


Case = Callable[[Path], tuple[list[str | Path], list[str]]]
BAD_INPUT: dict[str, Case] = {
    "track missing input": lambda t: (track(t, t / "absent.c3d"), ["absent.c3d", "no such file"]),
    "eval missing input": lambda t: (evaluate(t, t / "absent.trc"), ["absent.trc", "no such file"]),
    "markup in path": lambda t: (track(t, t / "take[/1].c3d"), ["take[/1].c3d"]),
    "truncated c3d": lambda t: (track(t, truncated_c3d(t)), ["half.c3d", "truncated"]),
    "unsupported suffix": lambda t: (track(t, wrong_suffix(t)), ["markers.xyz", ".xyz"]),
    "track window 1": lambda t: (track(t, CMU, "--window", "1"), ["window", "got 1"]),
    "track window 0": lambda t: (track(t, CMU, "--window", "0"), ["window", "got 0"]),
    "eval window 1": lambda t: (evaluate(t, CMU, "--window", "1"), ["--window", "got 1"]),
    "track formulation": lambda t: (track(t, CMU, "--formulation", "nope"), ["'nope'"]),
    "eval formulation": lambda t: (evaluate(t, CMU, "-f", "nope"), ["'nope'"]),
    "unknown scenario key": lambda t: (
        ["eval", CMU, "--scenario", write_scenario(t / "s.toml", 40, "bogus_key = 1\n")], ["bogus_key"]
    ),
    "track nan first frame": lambda t: (track(t, nan_first_frame_c3d(t)), ["Male:RBWT", "first frame"]),
    "eval nan first frame": lambda t: (evaluate(t, nan_first_frame_c3d(t)), ["Male:RBWT", "first frame"]),
    "c3d with every sample missing": lambda t: (track(t, all_missing_c3d(t)), ["none.c3d", "holds no point to label"]),
    "c3d without points": lambda t: (track(t, no_points_c3d(t)), ["empty.c3d", "no labeled points"]),
    "c3d with blank labels": lambda t: (track(t, blank_labels_c3d(t)), ["blank.c3d", "no point labels"]),
    "track out folder missing": lambda t: (["track", CMU, "-o", t / "nowhere" / "x.c3d"], ["nowhere", "cannot write"]),
    "track csv folder missing": lambda t: (["track", CMU, "-o", t / "nowhere" / "x.csv"], ["nowhere", "cannot write"]),
    "track out folder unwritable": lambda t: (["track", CMU, "-o", "/proc/x.c3d"], ["/proc", "cannot write"]),
    "track out is the input": lambda t: (["track", copied(t), "--start", "0", "-o", t / "." / "take.c3d"],
                                         ["take.c3d", "is the input"]),
    "boxes out is the input": lambda t: (["boxes", copied(t, "det.txt"), "-o", t / "det.txt"], ["det.txt", "is the input"]),
    "track out is a folder": lambda t: (["track", CMU, "-o", folder(t, "out.c3d")], ["out.c3d", "is a folder"]),
    "demo out is a file": lambda t: (["demo", "--out", existing_file(t), "--frames", "20"], ["taken", "folder"]),
}


@pytest.mark.parametrize("case", BAD_INPUT.values(), ids=BAD_INPUT.keys())
def test_bad_input_is_one_line_and_exit_code_2(case: Case, tmp_path: Path) -> None:
    args, words = case(tmp_path)
    assert_input_error(run_cli(*args), *words)


@pytest.mark.parametrize(("args", "words"), [
    (["track", "x.c3d", "--window", "abc"], ["Invalid value for '--window'", "(see markerflow track --help)"]),
    (["best-view", "c.csv", "--switch-cost", "abc", "--out", "o.csv"], ["Invalid value for '--switch-cost'"]),
    (["track"], ["Missing argument 'input'"]),
    (["tarck"], ["No such command 'tarck'", "(see markerflow --help)"]),
    (["track", "x.c3d", "-o", "y.c3d", "-q"], ["No such option: -q, which goes before the command: markerflow -q track"]),
])
def test_a_usage_mistake_is_one_line_like_any_other(args: list[str], words: list[str]) -> None:
    """Typer drew these as a six-line box under a usage line."""
    assert_input_error(run_cli(*args), *words)


def test_no_command_shows_the_help() -> None:
    shown = run_cli()
    assert "Usage: " in shown.stdout + shown.stderr and "error:" not in shown.stderr


@pytest.mark.parametrize(("db", "words"), [
    ("{tmp}/no/such/folder/jobs.db", ["cannot open the job store (unable to open database file)"]),
    (":memory:", ["in-memory SQLite database is private to each process"]),
    ("sqlite://", ["in-memory SQLite database is private to each process"]),
    ("nonsense://x", ["cannot open the job store"]),
])
def test_serve_refuses_a_store_it_cannot_use_in_one_line(tmp_path: Path, db: str, words: list[str]) -> None:
    """A missing folder was uvicorn's 172-line start-up traceback; an in-memory database served,
    and every job stayed queued (each worker process had its own empty database)."""
    assert_input_error(run_cli("serve", "--db", db.format(tmp=tmp_path), "--port", "0"), *words)


@pytest.mark.parametrize("address", ["127.0.0.1:8786x", "http://127.0.0.1:8000"])
def test_serve_refuses_a_dask_address_it_cannot_use_in_one_line(tmp_path: Path, address: str) -> None:
    """It was a 100-line start-up traceback (after a 30 s wait for an address that does not answer)."""
    assert_input_error(run_cli("serve", "--db", str(tmp_path / "jobs.db"), "--port", "0", "--dask", address),
                       f"--dask {address}: cannot reach the Dask scheduler (")
