"""Box tracking on short windows, sparse or huge frame numbers, and bad MOT files: tracks or one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from formulations.boxes.lifecycle import Lifecycle
from service.boxes.detections import BoxDetections
from service.boxes.mot_files import read_detections, read_seqinfo
from service.boxes.track import track_boxes
from service.cli.app import app
from service.errors import InputError

runner = CliRunner()


def _people(frames: range, people: int = 3) -> list[tuple[float, ...]]:
    """``people`` walkers far apart, one box per frame each."""
    return [(f, 100.0 + 300.0 * p + 2.0 * f, 200.0, 60.0, 150.0) for f in frames for p in range(people)]


def _detections(rows: list[tuple[float, ...]], n_frames: int) -> BoxDetections:
    r = np.array(rows)
    return BoxDetections(r[:, 0].astype(int), r[:, 1:], np.ones(len(r)), n_frames, (1920.0, 1080.0))


def _id(value: float) -> str:
    return str(int(value)) if value == int(value) else str(value)


def _mot(path: Path, rows: list[tuple[float, ...]], ids: list[float] | None = None) -> Path:
    ids = ids if ids is not None else [-1.0] * len(rows)
    path.write_text("".join(f"{r[0]:g},{_id(i)},{r[1]},{r[2]},{r[3]},{r[4]},0.9,-1,-1,-1\n" for r, i in zip(rows, ids)))
    return path


@pytest.mark.parametrize("formulation", ["lp-l1", "ilp"])
def test_window_of_two_tracks_everyone(formulation):
    run = track_boxes(_detections(_people(range(1, 21)), 20), formulation, window=2)
    assert len(set(run.tracks.track_id.tolist())) == 3
    assert len(run.tracks.frame) == 60


def test_window_of_two_matches_window_of_three_on_easy_walkers():
    detections = _detections(_people(range(1, 21)), 20)
    two, three = (track_boxes(detections, "lp-l1", window=w).tracks for w in (2, 3))
    assert sorted(zip(two.frame.tolist(), two.track_id.tolist())) == sorted(zip(three.frame.tolist(),
                                                                               three.track_id.tolist()))


def test_window_of_two_with_returns_compete_tracks():
    run = track_boxes(_detections(_people(range(1, 21)), 20), "lp-l1", window=2,
                      lifecycle=Lifecycle(returns_compete=True))
    assert len(run.tracks.frame) == 60


def test_an_empty_stretch_changes_nothing():
    # Frame numbers are bounded (``MAX_FRAMES``), so stepping through empty windows stays cheap.
    rows = _people(range(1, 11)) + _people(range(2_001, 2_011))
    sparse = track_boxes(_detections(rows, 2_010), "lp-l1", window=5).tracks
    assert len(sparse.frame) == 60 and len(set(sparse.track_id.tolist())) == 6


@pytest.mark.parametrize("line", [
    *(f"{frame},-1,10,10,5,5,0.9" for frame in ("100000000", "1e300", "-3", "2.5", "nan")),
    # a box at 1e300 px was taken (and overflowed the filter); nan, inf and text named no line
    *(f"2,-1,{cells}" for cells in ("1e300,10,5,5,0.9", "10,10,5,nan,0.9", "10,10,5,5,inf", "10,abc,5,5,0.9")),
])  # fmt: skip
def test_a_bad_line_is_named_in_one_line(tmp_path, line):
    path = tmp_path / "det.txt"
    path.write_text(f"1,-1,10,10,5,5,0.9\n{line}\n")
    with pytest.raises(InputError, match="line 2: ") as error:
        read_detections(path)
    assert "\n" not in str(error.value)


def test_frame_bound_is_documented_and_accepted(tmp_path):
    from service.boxes.mot_files import MAX_FRAMES
    path = tmp_path / "det.txt"
    path.write_text(f"1,-1,10,10,5,5,0.9\n{MAX_FRAMES},-1,10,10,5,5,0.9\n")
    assert read_detections(path).n_frames == MAX_FRAMES


@pytest.mark.parametrize(("text", "match"), [
    ("[Sequence]\nseqLength=-5\n", "seqLength -5 is invalid"),
    ("[Sequence]\nseqLength=0\n", "seqLength 0 is invalid"),
    ("[Sequence]\nseqLength=1000000\n", "seqLength 1000000 is invalid"),
    ("[Sequence]\nseqLength=30\nimWidth=0\nimHeight=1080\n", "imWidth"),
    ("[Sequence]\nseqLength=30\nframeRate=nan\n", "frameRate"),
])
def test_bad_seqinfo_values_are_named(tmp_path, text, match):
    path = tmp_path / "seqinfo.ini"
    path.write_text(text)
    with pytest.raises(InputError, match=match):
        read_seqinfo(path)


def test_binary_seqinfo_is_one_line(tmp_path):
    path = tmp_path / "seqinfo.ini"
    path.write_bytes(b"\x00\xff\xfe\x01\n\x02garbage\n")
    with pytest.raises(InputError) as error:
        read_seqinfo(path)
    assert "\n" not in str(error.value)


def test_cli_one_frame_sequence_is_a_clear_error(tmp_path):
    det = _mot(tmp_path / "det.txt", _people(range(1, 2)))
    run = runner.invoke(app, ["boxes", str(det), "--out", str(tmp_path / "r.txt")])
    assert run.exit_code == 2 and "at least 2" in run.output and len(run.output.strip().splitlines()) == 1


def test_cli_window_two_writes_tracks(tmp_path):
    det = _mot(tmp_path / "det.txt", _people(range(1, 21)))
    run = runner.invoke(app, ["boxes", str(det), "--out", str(tmp_path / "r.txt"), "-w", "2"])
    assert run.exit_code == 0, run.output
    assert len((tmp_path / "r.txt").read_text().splitlines()) == 60


def _gt(path: Path, rows: list[tuple[float, ...]], ids: list[float]) -> Path:
    path.write_text("".join(f"{r[0]:g},{_id(i)},{r[1]},{r[2]},{r[3]},{r[4]},1,1,1\n" for r, i in zip(rows, ids)))
    return path


def test_mot_eval_scores_huge_ids_as_small_ones(tmp_path):
    rows = _people(range(1, 11), people=2)
    small = [1.0 + (k % 2) for k in range(len(rows))]
    huge = [1e15 + (k % 2) for k in range(len(rows))]
    gt = _gt(tmp_path / "gt.txt", rows, small)
    gt_huge = _gt(tmp_path / "gt_huge.txt", rows, huge)
    res = _mot(tmp_path / "res.txt", rows, small)
    res_huge = _mot(tmp_path / "res_huge.txt", rows, huge)
    from service.boxes.scores import mot_scores
    reference = mot_scores(res, gt).as_dict()
    assert mot_scores(res_huge, gt).as_dict() == reference
    assert mot_scores(res, gt_huge).as_dict() == reference
    assert reference["hota"] > 0.9


@pytest.mark.parametrize("which", ["gt", "res"])
def test_mot_eval_fractional_id_names_the_line(tmp_path, which):
    rows = _people(range(1, 4), people=1)
    ids = [1.0, 2.5, 1.0]
    gt = _gt(tmp_path / "gt.txt", rows, ids if which == "gt" else [1.0] * 3)
    res = _mot(tmp_path / "res.txt", rows, ids if which == "res" else [1.0] * 3)
    run = runner.invoke(app, ["mot-eval", str(res), str(gt)])
    assert run.exit_code == 2, run.output
    assert "line 2" in run.output and "2.5" in run.output and len(run.output.strip().splitlines()) == 1


def test_mot_eval_scores_do_not_depend_on_frames_after_the_last_box(tmp_path):
    from service.boxes.scores import mot_scores
    rows = _people(range(1, 11), people=2)
    ids = [1.0 + (k % 2) for k in range(len(rows))]
    gt, res = _gt(tmp_path / "gt.txt", rows, ids), _mot(tmp_path / "res.txt", rows, ids)
    (tmp_path / "short.ini").write_text("[Sequence]\nseqLength=10\n")
    (tmp_path / "long.ini").write_text("[Sequence]\nseqLength=100000\n")
    short = mot_scores(res, gt, tmp_path / "short.ini").as_dict()
    long = mot_scores(res, gt, tmp_path / "long.ini").as_dict()
    assert {**short, "frames": 100000} == long  # frames after the last box change no score


def test_cli_warns_when_a_long_window_leaves_people_untracked(tmp_path):
    """MOT17-02's first 60 frames (MPNTrack's boxes, ids dropped): window 30 tracks 380 of
    687 boxes, silently; the default window tracks them all and says nothing."""
    source = Path(__file__).resolve().parents[2] / "shared" / "data" / "mot17_train_gt_and_tracker_outputs"
    rows = [line.split(",") for line in (source / "MOT17-02-FRCNN" / "trackers" / "MPNTrack.txt").read_text().split()]
    det = tmp_path / "det.txt"
    det.write_text("".join(",".join([r[0], "-1", *r[2:7]]) + "\n" for r in rows if int(float(r[0])) <= 60))
    for window, warned in (("5", False), ("30", True)):
        run = runner.invoke(app, ["boxes", str(det), "--out", str(tmp_path / "r.txt"), "-w", window, "--json"])
        assert run.exit_code == 0, run.output
        assert ("of the detections are in no track at --window 30" in run.output) == warned
