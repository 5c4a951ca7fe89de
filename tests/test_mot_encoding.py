"""MOTChallenge files saved with a UTF-8 byte-order mark (a Windows editor, a spreadsheet) are
read as without it, as capture JSON, TOML and best-view's COSTS.csv are: det.txt was refused
with "not a number ('\\ufeff1')", and a seqinfo.ini had "no section headers"."""

from __future__ import annotations

from pathlib import Path

import motmetrics
import numpy as np
import pytest
from typer.testing import CliRunner

from service.boxes.mot_files import read_detections, read_seqinfo, read_table
from service.boxes.scores import mot_scores
from service.cli.app import app
from service.errors import InputError

BOM = b"\xef\xbb\xbf"
TUD = Path(motmetrics.__file__).parent / "data" / "TUD-Campus"


def _with_bom(source: Path, path: Path) -> Path:
    path.write_bytes(BOM + source.read_bytes())
    return path


def test_a_det_txt_with_a_byte_order_mark_reads_as_without(tmp_path: Path) -> None:
    marked = read_detections(_with_bom(TUD / "test.txt", tmp_path / "det.txt"))
    plain = read_detections(TUD / "test.txt")
    assert np.array_equal(marked.frame, plain.frame) and np.array_equal(marked.box, plain.box)
    assert read_table(tmp_path / "det.txt").lines[0] == 1  # the mark is no line of its own


def test_boxes_and_mot_eval_take_marked_files(tmp_path: Path) -> None:
    runner = CliRunner()
    det = _with_bom(TUD / "test.txt", tmp_path / "det.txt")
    run = runner.invoke(app, ["-q", "boxes", str(det), "--out", str(tmp_path / "r.txt"), "--json"])
    assert run.exit_code == 0, run.output
    gt = _with_bom(TUD / "gt.txt", tmp_path / "gt.txt")
    result = _with_bom(TUD / "test.txt", tmp_path / "result.txt")
    assert mot_scores(result, gt).as_dict() == mot_scores(TUD / "test.txt", TUD / "gt.txt").as_dict()


def test_a_seqinfo_with_a_byte_order_mark_reads_as_without(tmp_path: Path) -> None:
    path = tmp_path / "seqinfo.ini"
    path.write_bytes(BOM + b"[Sequence]\nname=TUD-Campus\nseqLength=71\nimWidth=640\nimHeight=480\n")
    info = read_seqinfo(path)
    assert (info.length, info.image_size, info.name) == (71, (640.0, 480.0), "TUD-Campus")


@pytest.mark.parametrize("name", ["det.txt", "seqinfo.ini"])
def test_a_file_not_utf8_is_one_line_naming_it(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    path.write_bytes(b"1,-1,\xff\xfe,2,3,4,0.9\n")
    reader = read_seqinfo if name.endswith(".ini") else read_detections
    with pytest.raises(InputError, match=rf"{name}: not UTF-8 text \(byte 6 is 0xff\); save it as UTF-8$"):
        reader(path)
