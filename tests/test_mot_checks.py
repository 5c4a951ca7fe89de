"""mot-eval: the benchmark's rules, repeated ids, extra columns and a result of another
sequence are said in one line naming the file and line, not scored silently or passed on as
TrackEval's words (a placeholder sequence and renumbered ids)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import motmetrics
import numpy as np
import pytest
from typer.testing import CliRunner

from service.boxes.scores import mot_scores
from service.cli.app import app
from service.errors import InputError

runner = CliRunner()
TUD = Path(motmetrics.__file__).parent / "data" / "TUD-Campus"


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines()


def _write(path: Path, lines: list[str]) -> Path:
    path.write_text("".join(line + "\n" for line in lines))
    return path


def _as_mot17(tmp_path: Path, first_class: str = "1") -> Path:
    """TUD-Campus's gt in MOT17's 9 columns (consider, class, visibility), the first line's class given."""
    rows = [line.split(",")[:7] + ["1", "1"] for line in _lines(TUD / "gt.txt")]
    rows[0][7] = first_class
    return _write(tmp_path / "gt17.txt", [",".join(row) for row in rows])


def test_a_stray_class_in_a_mot17_ground_truth_is_named_not_scored_by_mot15_rules(tmp_path: Path) -> None:
    result = TUD / "test.txt"
    assert mot_scores(result, _as_mot17(tmp_path)).hota > 0.3  # MOT17 rules apply to a clean file
    with pytest.raises(InputError, match=r"gt17.txt: line 1: class 0; a 9-column ground truth"):
        mot_scores(result, _as_mot17(tmp_path, "0"))


def test_an_id_twice_in_one_frame_names_both_lines(tmp_path: Path) -> None:
    lines = _lines(TUD / "test.txt")
    frame, ident = lines[0].split(",")[:2]
    twin = ",".join([frame, ident] + lines[1].split(",")[2:])
    result = _write(tmp_path / "r.txt", [lines[0], "", twin] + lines[2:])
    with pytest.raises(InputError, match=rf"r.txt: line 3: id {ident} appears twice in frame {frame} \(also line 1\)"):
        mot_scores(result, TUD / "gt.txt")


def test_a_seven_column_ground_truth_is_scored(tmp_path: Path) -> None:
    gt = _write(tmp_path / "gt7.txt", [",".join(line.split(",")[:7]) for line in _lines(TUD / "gt.txt")])
    assert mot_scores(TUD / "test.txt", gt).as_dict() == mot_scores(TUD / "test.txt", TUD / "gt.txt").as_dict()


def test_a_results_world_coordinates_are_not_read_as_a_class(tmp_path: Path) -> None:
    """MOT15 results may carry world x, y, z; TrackEval read x as a class (> 1: 'non pedestrian')."""
    rows = [line.split(",")[:7] + ["3.5", "2.0", "0"] for line in _lines(TUD / "test.txt")]
    result = _write(tmp_path / "r.txt", [",".join(row) for row in rows])
    assert mot_scores(result, TUD / "gt.txt").as_dict() == mot_scores(TUD / "test.txt", TUD / "gt.txt").as_dict()


def test_a_result_of_another_place_is_scored_with_a_warning(tmp_path: Path) -> None:
    rows = np.loadtxt(TUD / "test.txt", delimiter=",")
    rows[:, 2] += 2000.0  # every box elsewhere in the image
    moved = tmp_path / "moved.txt"
    np.savetxt(moved, rows, fmt="%.6g", delimiter=",")
    assert mot_scores(moved, TUD / "gt.txt").matched == 0.0
    assert mot_scores(TUD / "test.txt", TUD / "gt.txt").matched > 0.8
    run = runner.invoke(app, ["mot-eval", str(moved), str(TUD / "gt.txt"), "--json"])
    assert run.exit_code == 0 and "warning: only 0% of the boxes" in run.stderr


def test_blank_lines_count_in_the_line_named(tmp_path: Path) -> None:
    lines = _lines(TUD / "test.txt")
    result = _write(tmp_path / "r.txt", lines[:2] + ["", "", lines[2].replace(",", ",x", 1)] + lines[3:])
    with pytest.raises(InputError, match=r"r.txt: line 5: not a number"):
        mot_scores(result, TUD / "gt.txt")


def test_a_space_separated_file_is_told_so(tmp_path: Path) -> None:
    result = _write(tmp_path / "r.txt", [line.replace(",", " ") for line in _lines(TUD / "test.txt")])
    with pytest.raises(InputError, match="separated by spaces or tabs"):
        mot_scores(result, TUD / "gt.txt")


def test_a_result_given_as_the_ground_truth_is_refused(tmp_path: Path) -> None:
    """A tracker's confidences in column 7 scored as consider flags (MOT17-09: HOTA 0.240, MOTA -5.98)."""
    rows = [line.split(",") for line in _lines(TUD / "test.txt")]
    result = _write(tmp_path / "r.txt", [",".join(row[:6] + ["0.9866"] + row[7:]) for row in rows])
    with pytest.raises(InputError, match=r"r.txt: line 1: 0.9866 in column 7, where a ground truth has its consider flag"):
        mot_scores(TUD / "gt.txt", result)


def test_a_ground_truth_with_nothing_to_consider_is_refused(tmp_path: Path) -> None:
    gt = _write(tmp_path / "gt.txt", [",".join(line.split(",")[:6] + ["0"] + line.split(",")[7:])
                                      for line in _lines(TUD / "gt.txt")])
    with pytest.raises(InputError, match="counts none of its boxes as ground truth"):
        mot_scores(TUD / "test.txt", gt)


def test_an_empty_result_has_no_matched_share(tmp_path: Path) -> None:
    """A tracker that reported no one read as ``"matched": 1.0``, every box on the ground truth."""
    empty = _write(tmp_path / "empty.txt", [])
    scores = mot_scores(empty, TUD / "gt.txt")
    assert scores.matched is None and scores.hota == 0
    run = runner.invoke(app, ["mot-eval", str(empty), str(TUD / "gt.txt"), "--json"])
    assert run.exit_code == 0 and json.loads(run.stdout)["matched"] is None
    assert "warning" not in run.stderr  # the scores of 0 say it; "only 0% overlap" would ask the wrong question
    table = runner.invoke(app, ["mot-eval", str(empty), str(TUD / "gt.txt")])
    assert table.exit_code == 0 and re.search(r"result boxes on a ground-truth box\s*│\s*-\s*│", table.stdout)


def _seqinfo(tmp_path: Path, length: int) -> Path:
    path = tmp_path / "seqinfo.ini"
    path.write_text(f"[Sequence]\nname=other\nseqLength={length}\n")
    return path


def test_a_seqinfo_longer_than_the_ground_truth_is_warned_of(tmp_path: Path) -> None:
    """Another sequence's seqinfo.ini (MOT17-05's 837 frames for MOT17-02's 600) was taken silently."""
    last = int(np.loadtxt(TUD / "gt.txt", delimiter=",")[:, 0].max())
    longer = _seqinfo(tmp_path, last + 237)
    run = runner.invoke(app, ["mot-eval", str(TUD / "test.txt"), str(TUD / "gt.txt"), "--seqinfo", str(longer), "--json"])
    assert run.exit_code == 0 and json.loads(run.stdout)["frames"] == last + 237
    warnings = [line for line in run.stderr.splitlines() if line.startswith("warning:")]
    assert warnings == [f"warning: the ground truth ends at frame {last} of the sequence's {last + 237} ({longer}); "
                        "is that seqinfo.ini of another sequence?"]
    same = runner.invoke(app, ["mot-eval", str(TUD / "test.txt"), str(TUD / "gt.txt"), "--seqinfo",
                               str(_seqinfo(tmp_path, last)), "--json"])
    assert same.exit_code == 0 and "warning" not in same.stderr
    with pytest.raises(InputError, match=rf"frame {last} of the ground truth is past the sequence's {last - 1} frames"):
        mot_scores(TUD / "test.txt", TUD / "gt.txt", _seqinfo(tmp_path, last - 1))
