"""``markerflow track REC.c3d --start S [--end E]`` without a model: the take's own labels at
frame S start the labeling, markers absent there stay unlabeled (and are named on stderr),
and the output is the whole input with frames outside S..E-1 present and unlabeled.
Checked with ezc3d on the written file, not with markerflow's reader."""

from __future__ import annotations

import json
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from conftest import DATA
from test_subject_model import chain
from typer.testing import CliRunner

from service.cli.app import app

FIRST = 11  # the input's first frame number
START, END, FRAMES = 60, 200, 240
GAP = {0: slice(0, 40), 5: slice(55, 70)}  # marker -> frames it is missing: 5 is absent at START
VICON = DATA / "c3d_ezc3d_testfiles" / "Vicon.c3d"


def _take(path: Path) -> tuple[list[str], np.ndarray]:
    """A clean generated take as C3D (mm, numbered from FIRST, two analog channels at twice
    the point rate), markers missing in the ``GAP`` frames; its names and ``(3, N, F)`` points."""
    names, positions, _ = chain(2, frames=FRAMES)
    points = positions.transpose(2, 1, 0).copy()
    residual = np.zeros(points.shape[1:])
    for marker, frames in GAP.items():
        points[:, marker, frames], residual[marker, frames] = 0.0, -1.0
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = names
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c3d["header"]["points"]["first_frame"] = FIRST
    c3d["data"]["points"] = np.concatenate([points, np.ones((1,) + points.shape[1:])])
    c3d["data"]["meta_points"]["residuals"] = residual[None]
    c3d["parameters"]["ANALOG"]["RATE"]["value"] = np.array([200.0])
    c3d["parameters"]["ANALOG"]["LABELS"]["value"] = ["EMG1", "FZ"]
    c3d["parameters"]["ANALOG"]["UNITS"]["value"] = ["V", "N"]
    c3d["data"]["analogs"] = np.random.default_rng(3).normal(0, 1, (1, 2, 2 * FRAMES))
    c3d.write(str(path))
    return names, np.where(residual[None] < 0, np.nan, points)


def _track(*args: str | Path | int) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, ["track", *map(str, args)])
    return result.exit_code, result.stdout, result.stderr


def _labels(path: Path) -> tuple[ezc3d.c3d, np.ndarray, np.ndarray]:
    """The written C3D, its ``(3, N, F)`` points and ``(N, F)`` labeled (residual >= 0)."""
    c3d = ezc3d.c3d(str(path))
    return c3d, c3d["data"]["points"][:3], c3d["data"]["meta_points"]["residuals"][0] >= 0


def test_start_relabels_from_the_takes_own_labels_and_keeps_the_whole_file(tmp_path: Path) -> None:
    source, out = tmp_path / "take.c3d", tmp_path / "out.c3d"
    names, truth = _take(source)
    code, _, stderr = _track(source, "--start", START, "--end", END, "--out", out)
    assert code == 0, stderr
    assert f"1 marker absent at frame {START}, not labeled" in stderr and names[5] in stderr
    given = ezc3d.c3d(str(source))
    written, points, labeled = _labels(out)
    n = len(names)  # the input's points, then its samples outside the span kept unlabeled (*N)
    points, labeled, unlabeled = points[:, :n], labeled[:n], points[:, n:]
    outside = np.r_[0:START, END : truth.shape[2]]
    assert np.isfinite(unlabeled[:, :, outside]).all(axis=0).sum() == np.isfinite(truth[:, :, outside]).all(axis=0).sum()

    assert written["header"]["points"]["first_frame"] == FIRST
    assert points.shape == truth.shape  # every input frame, numbered as in the input
    assert [str(label).strip() for label in written["parameters"]["POINT"]["LABELS"]["value"]][:n] == names
    assert [str(label).strip() for label in written["parameters"]["ANALOG"]["LABELS"]["value"]][:2] == ["EMG1", "FZ"]
    np.testing.assert_allclose(written["data"]["analogs"][:, :2], given["data"]["analogs"], atol=1e-6)

    assert not labeled[:, :START].any() and not labeled[:, END:].any()  # outside the span: present, unlabeled
    assert np.isnan(points[:, :, :START]).all() and np.isnan(points[:, :, END:]).all()
    assert not labeled[5].any()  # absent at START: never labeled, even where it reappears
    kept = [m for m in range(len(names)) if m != 5]
    own = np.isfinite(truth[:, kept, START:END]).all(axis=0)
    assert (labeled[kept, START:END] == own).all()  # a clean take: every present sample labeled, nothing else
    np.testing.assert_allclose(points[:, kept, START:END][:, own], truth[:, kept, START:END][:, own], atol=1e-3)


def test_trc_output_holds_the_span_numbered_as_in_the_input(tmp_path: Path) -> None:
    source, out = tmp_path / "take.c3d", tmp_path / "out.trc"
    _take(source)
    code, _, stderr = _track(source, "--start", START, "--end", END, "--out", out)
    assert code == 0, stderr
    rows = [line.split("\t") for line in out.read_text().splitlines()[5:] if line.strip()]
    assert len(rows) == END - START
    # the columns in the input's order, the marker absent at START among them where it was (it came last)
    assert [name for name in out.read_text().splitlines()[3].split("\t")[2:] if name] == _take(tmp_path / "again.c3d")[0]
    assert [int(row[0]) for row in (rows[0], rows[-1])] == [FIRST + START + 1, FIRST + END]  # TRC counts from 1


def test_without_start_a_take_lacking_a_marker_in_frame_0_is_refused_with_a_hint(tmp_path: Path) -> None:
    source = tmp_path / "take.c3d"
    names, _ = _take(source)
    code, stdout, stderr = _track(source, "--out", tmp_path / "out.c3d")
    assert code == 2 and not (tmp_path / "out.c3d").exists()
    assert names[0] in stderr and "--start " in stderr and len(stderr.strip().splitlines()) == 1
    suggested = int(stderr.split("--start ")[1].split()[0])
    code, _, stderr = _track(source, "--start", str(suggested), "--out", tmp_path / "out.c3d")
    assert code == 0 and "absent at frame" not in stderr  # the frame suggested has every marker


@pytest.mark.parametrize("span", [
    ("--start", str(FRAMES - 1)), ("--start", "-1"), ("--start", "100", "--end", "100"),
    ("--start", "100", "--end", "50"), ("--start", "100", "--end", str(FRAMES + 1)),
])  # fmt: skip
def test_a_span_outside_the_take_is_one_line(span: tuple[str, ...], tmp_path: Path) -> None:
    source = tmp_path / "take.c3d"
    _take(source)
    code, _, stderr = _track(source, *span, "--out", tmp_path / "out.c3d")
    assert code == 2 and len(stderr.strip().splitlines()) == 1
    # what was given, not an --end the user never wrote, and how frames are counted
    assert stderr.startswith(f"error: {' '.join(span)}: frames are counted from 0 at the take's first"), stderr


def test_a_one_frame_take_is_one_line_that_says_so(tmp_path: Path) -> None:
    source = tmp_path / "one.c3d"
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ["A", "B", "C"]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c3d["data"]["points"] = np.concatenate([np.arange(9.0).reshape(3, 3, 1), np.ones((1, 3, 1))])
    c3d.write(str(source))
    code, _, stderr = _track(source, "--out", tmp_path / "out.c3d")
    assert code == 2 and stderr.strip() == "error: one.c3d: the take has 1 frame; labeling needs at least 2"


def test_a_capture_json_takes_no_start_without_a_model(tmp_path: Path) -> None:
    document = tmp_path / "capture.json"
    document.write_text('{"markers": ["A"], "first_frame": [[0, 0, 0]], "rate": 100, "frames": [[[0, 0, 0]], [[0, 0, 1]]]}')
    code, _, stderr = _track(document, "--start", "1", "--out", tmp_path / "out.csv")
    assert code == 2 and "needs --model" in stderr


def test_a_capture_json_takes_an_end(tmp_path: Path) -> None:
    """Frame 0's labels are enough to label frames 0 .. end - 1 (--end was refused with --start)."""
    document, out = tmp_path / "capture.json", tmp_path / "out.csv"
    frames = [[[0.0, 0.0, 0.0], [50.0, 0.0, 0.0]]] + [[[0.0, 0.0, k], [50.0, 0.0, k]] for k in range(1, 10)]
    document.write_text(json.dumps({"markers": ["A", "B"], "first_frame": frames[0], "rate": 100, "points": frames}))
    code, _, stderr = _track(document, "--end", "4", "--out", out)
    assert code == 0, stderr
    assert len(out.read_text().splitlines()) == 1 + 4  # the header and frames 0-3
    code, _, stderr = _track(document, "--end", "11", "--out", out)
    assert code == 2 and "start + 2 <= end <= 10" in stderr


@pytest.mark.skipif(not VICON.exists(), reason="needs ../shared/data")
def test_real_take_from_a_frame_with_absent_markers(tmp_path: Path) -> None:
    """Vicon.c3d (38 analog channels) from frame 140, where two markers are missing."""
    start, end, out = 140, 220, tmp_path / "out.c3d"
    code, _, stderr = _track(VICON, "--start", start, "--end", end, "--out", out)
    assert code == 0, stderr
    given = ezc3d.c3d(str(VICON))
    written, points, labeled = _labels(out)
    truth = given["data"]["points"][:3]
    points, labeled = points[:, : truth.shape[1]], labeled[: truth.shape[1]]  # then the unlabeled *N
    present = np.isfinite(truth).all(axis=0) & ~(truth == 0).all(axis=0)
    absent = np.flatnonzero(~present[:, start])
    names = [str(label).strip() for label in given["parameters"]["POINT"]["LABELS"]["value"]]
    assert len(absent) == 2 and all(names[m] in stderr for m in absent)
    assert written["data"]["points"][:, : truth.shape[1]].shape == given["data"]["points"].shape
    assert written["header"]["points"]["first_frame"] == given["header"]["points"]["first_frame"]
    np.testing.assert_array_equal(written["data"]["analogs"][:, :38], given["data"]["analogs"])
    assert not labeled[:, :start].any() and not labeled[:, end:].any() and not labeled[absent].any()
    kept = np.setdiff1d(np.arange(len(names)), absent)
    span = slice(start, end)
    same = np.linalg.norm(points[:, kept, span] - truth[:, kept, span], axis=0) < 1e-3
    # The absent markers' points stay in the frames, unnamed: a kept marker may take one when it
    # reappears near it. At 169 MEDH vanishes as STYLu appears 33 mm from it; an unnamed track is
    # born there, but the window still gives it to MEDH, which keeps it to the end, and LASTC
    # takes MEDH's point when it is back at 189 (2.1 % of labels; before unnamed tracks MEDH let
    # go at 188 and the two were wrong 23 frames, 1.4 %: docs/how-a-window-is-solved.md, "Unnamed tracks").
    assert same[labeled[kept, span]].mean() >= 0.975
    assert labeled[kept, span][present[kept, span]].mean() >= 0.99
