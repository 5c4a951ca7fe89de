"""``model``, ``boxes`` and ``best-view`` refuse an output they cannot write before the work,
as ``track`` does (``check_writable_output``): a folder as ``--out`` printed a model's tables,
or tracked a whole sequence, and only then said "cannot write (Is a directory)"."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from test_cli import DATA, assert_input_error, run_cli

import service.cli.best_view as best_view
import service.cli.boxes as boxes
import service.cli.model as model
from service.errors import InputError

WALK = DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc"
DETECTIONS = DATA / "mot15_sort_frcnn_detections" / "TUD-Campus" / "det.txt"


def _costs(tmp_path: Path) -> Path:
    path = tmp_path / "costs.csv"
    path.write_text("frame,object,camera,cost\n1,a,c1,0.5\n1,a,c2,0.3\n2,a,c1,0.4\n2,a,c2,0.6\n", encoding="utf-8")
    return path


def _no_work(*args: object, **kwargs: object) -> None:
    raise AssertionError("read the input before refusing the output")


COMMANDS: dict[str, tuple[str, Callable[[Path], Path], Callable[[Path, Path], None]]] = {
    # the command, its input, and a call of its run function that fails if it reads the input
    "model": ("read_labeled", lambda tmp: WALK, lambda given, out: model.run_model([given], out, None)),
    "boxes": ("read_detections", lambda tmp: DETECTIONS,
              lambda given, out: boxes.run_boxes(given, out, "lp-l1", None, None, 5, False)),
    "best-view": ("read_view_costs", _costs, lambda given, out: best_view.run_best_view(given, out, 1.0, 5)),
}
MODULES = {"model": model, "boxes": boxes, "best-view": best_view}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_folder_as_the_output_is_refused_before_the_work(command: str, tmp_path: Path) -> None:
    reader, given, run = COMMANDS[command]
    folder = tmp_path / "out.json"  # a .json name, so model's own suffix check lets it through
    folder.mkdir()
    result = run_cli("-q", command, given(tmp_path), "--out", folder)
    assert_input_error(result, "out.json: is a folder; name the output file")
    assert result.stdout == ""  # no table of a fitted model, no tracking figures


@pytest.mark.parametrize("command", list(COMMANDS))
def test_the_output_checks_of_track_come_before_reading(
    command: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    reader, given, run = COMMANDS[command]
    source = given(tmp_path)
    monkeypatch.setattr(MODULES[command], reader, _no_work)
    (tmp_path / "taken.json").mkdir()
    with pytest.raises(InputError, match="taken.json: is a folder"):
        run(source, tmp_path / "taken.json")
    with pytest.raises(InputError, match=r"cannot write there, folder .*missing does not exist"):
        run(source, tmp_path / "missing" / "out.json")


@pytest.mark.parametrize("command", ["boxes", "best-view"])
def test_the_input_as_the_output_is_still_refused(command: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    reader, given, run = COMMANDS[command]
    source = tmp_path / "input.txt"
    source.write_bytes(given(tmp_path).read_bytes())
    monkeypatch.setattr(MODULES[command], reader, _no_work)
    with pytest.raises(InputError, match="is the input"):
        run(source, source)
