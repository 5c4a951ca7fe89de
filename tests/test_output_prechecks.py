"""What the output cannot take is said before the labeling, not after it: a TRC whose Frame#
starts at 70000 labeled every window before "a C3D numbers frames up to 65535"."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_cli import DATA, assert_input_error, run_cli

import service.cli.track as track
from service.errors import InputError

WALK = DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc"


def _renumbered(path: Path, first: int, rows: int = 30) -> Path:
    """The first ``rows`` frames of the OpenSim walk, its Frame# counted from ``first``."""
    lines = WALK.read_text(encoding="utf-8").splitlines()
    header, data = lines[:6], [line for line in lines[6:] if line.strip()][:rows]
    values = header[2].split("\t")
    values[2] = str(rows)
    header[2] = "\t".join(values)
    data = ["\t".join([str(first + i)] + line.split("\t")[1:]) for i, line in enumerate(data)]
    path.write_text("\n".join(header + data) + "\n", encoding="utf-8")
    return path


class _NoLabeling:
    def __init__(self, *args: object, **kwargs: object) -> None:
        raise AssertionError("labeled before refusing the output")


def test_frame_numbers_past_65535_are_refused_for_a_c3d_before_labeling(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    take = _renumbered(tmp_path / "late.trc", 70000)
    monkeypatch.setattr(track, "CaptureLabeling", _NoLabeling)
    with pytest.raises(InputError, match=r"out.c3d: a C3D numbers frames up to 65535 .*write .trc or .csv"):
        track.run_track(take, tmp_path / "out.c3d", None, None, False)
    assert not (tmp_path / "out.c3d").exists()


def test_frame_numbers_that_fit_pass_the_check(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    take = _renumbered(tmp_path / "late.trc", 65000)
    monkeypatch.setattr(track, "CaptureLabeling", _NoLabeling)
    with pytest.raises(AssertionError, match="labeled before"):
        track.run_track(take, tmp_path / "out.c3d", None, None, False)


def test_track_says_so_in_one_line(tmp_path: Path) -> None:
    take = _renumbered(tmp_path / "late.trc", 70000)
    assert_input_error(run_cli("track", take, "--out", tmp_path / "out.c3d"), "out.c3d", "65535")
    result = run_cli("-q", "track", take, "--out", tmp_path / "out.trc")  # a table keeps any number
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out.trc").read_text(encoding="utf-8").splitlines()[6].startswith("70000\t")
