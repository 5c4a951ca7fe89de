"""TRC and CSV tables saved as Windows does (code page 1252) or with a UTF-8 byte-order mark
read with their names intact: a cp1252 name came back with U+FFFD in place of its accent
(written so, and two such names collided), and a TRC with a BOM was "not a TRC file"."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories

NAMES = ["R.Épine", "L.Épine", "Sternum°"]


def _table(path: Path) -> Path:
    positions = np.random.default_rng(0).uniform(-500, 500, (5, len(NAMES), 3))
    write_labeled(path, LabeledTrajectories(NAMES, positions, np.zeros((5, len(NAMES)), bool), 100.0))
    return path


@pytest.mark.parametrize("suffix", [".trc", ".csv"])
@pytest.mark.parametrize("encoding", ["cp1252", "utf-8-sig"])
def test_names_survive_the_encodings_lab_pcs_save_in(tmp_path: Path, suffix: str, encoding: str) -> None:
    written = _table(tmp_path / f"utf8{suffix}")
    saved = tmp_path / f"saved{suffix}"
    saved.write_bytes(written.read_text(encoding="utf-8").encode(encoding))
    assert read_labeled(saved).names == NAMES
    np.testing.assert_allclose(read_labeled(saved).positions, read_labeled(written).positions)


def test_a_binary_file_named_trc_is_refused_in_one_line(tmp_path: Path) -> None:
    junk = tmp_path / "junk.trc"
    junk.write_bytes(b"PathFileType\t4\n\x81\x8d\x8f\x90\x9d" * 10)
    with pytest.raises(InputError, match=r"junk.trc: not text in UTF-8 or Windows-1252"):
        read_labeled(junk)


@pytest.mark.parametrize(("rate", "decimals", "rows", "read"), [
    (120.0, 3, 124, 120.0),  # read 119.96 from times rounded to milliseconds
    (69.99, 6, 700, 69.99),  # a rate that is not whole stays what the times say
    (100.0, 9, 50, 100.0),
])
def test_a_csv_rate_is_read_through_the_rounding_of_its_times(tmp_path: Path, rate: float, decimals: int, rows: int,
                                                              read: float) -> None:
    times = [f"{k / rate:.{decimals}f}" for k in range(rows)]
    lines = ["frame,time,A_x,A_y,A_z"] + [f"{k + 1},{t},{k}.0,0,0" for k, t in enumerate(times)]
    (tmp_path / "t.csv").write_text("\n".join(lines) + "\n")
    assert read_labeled(tmp_path / "t.csv").rate == read
