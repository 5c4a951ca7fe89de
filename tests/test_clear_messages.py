"""Messages that say what is wrong: a semicolon-separated CSV dumped its whole second row
("could not convert string to float: '1;0.0;116.39...'"), ``--out folder/`` said "cannot
write a file without suffix", and a blank line inside a CSV was refused ("0 cells, header
has 166") where a TRC skips it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_cli import CMU, assert_input_error, run_cli

from service.errors import InputError
from service.io.formats import check_output, read_labeled, write_labeled
from tests.test_formats import _occluded_cmu


def _csv(path: Path) -> Path:
    traj = _occluded_cmu(frames=6)
    traj.confidence = np.full((6, len(traj.names)), 0.75)
    write_labeled(path, traj)
    return path


def test_a_semicolon_separated_csv_says_so_on_line_1(tmp_path: Path) -> None:
    path = _csv(tmp_path / "semi.csv")
    path.write_text(path.read_text(encoding="utf-8").replace(",", ";"), encoding="utf-8")
    with pytest.raises(InputError) as error:
        read_labeled(path)
    assert str(error.value).startswith(f"{path}:1: the cells are separated by ';'; a markerflow CSV separates "
                                       "them by ','")
    assert len(str(error.value).removeprefix(str(path))) < 160  # no row dumped


def test_blank_lines_in_a_csv_are_skipped_as_in_a_trc(tmp_path: Path) -> None:
    path = _csv(tmp_path / "take.csv")
    lines = path.read_text(encoding="utf-8").splitlines()
    spaced = tmp_path / "spaced.csv"
    spaced.write_text("\n".join(lines[:3] + ["", "  "] + lines[3:] + [""]) + "\n", encoding="utf-8")
    original, read = read_labeled(path), read_labeled(spaced)
    assert read.names == original.names and read.rate == original.rate
    np.testing.assert_array_equal(read.positions, original.positions)


def test_a_bad_cell_after_a_blank_line_names_its_own_line(tmp_path: Path) -> None:
    path = _csv(tmp_path / "take.csv")
    lines = path.read_text(encoding="utf-8").splitlines()
    lines[4] = lines[4].replace(",", ",x", 1)
    path.write_text("\n".join(lines[:3] + [""] + lines[3:]) + "\n", encoding="utf-8")
    with pytest.raises(InputError, match=rf"^{path}:6: could not convert"):  # line 5 of the table, 6 of the file
        read_labeled(path)


def test_an_output_folder_with_its_trailing_slash_is_a_folder(tmp_path: Path) -> None:
    (tmp_path / "results").mkdir()
    with pytest.raises(InputError, match=r"results/?: is a folder; name the output file"):
        check_output(f"{tmp_path / 'results'}/")
    assert_input_error(run_cli("track", CMU, "--out", f"{tmp_path / 'results'}/"), "results: is a folder")

