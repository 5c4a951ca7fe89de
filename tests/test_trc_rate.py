"""A TRC's DataRate must agree with its Time column: DataRate 120 over times 1/60 s apart was
read silently and labeled (and written back) at 120 Hz. Refused in one line naming both
rates, as a NumFrames that disagrees with the rows is."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_cli import DATA

from service.errors import InputError
from service.io.formats import read_labeled

WALK = DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc"  # 60 Hz, times printed to 3 decimals


def _with_rate(path: Path, rate: str, rows: int = 30) -> Path:
    lines = WALK.read_text(encoding="utf-8").splitlines()
    header, data = lines[:6], [line for line in lines[6:] if line.strip()][:rows]
    values = header[2].split("\t")
    values[0], values[2] = rate, str(rows)
    header[2] = "\t".join(values)
    path.write_text("\n".join(header + data) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("rate", ["120.00", "30", "50"])
def test_a_data_rate_the_times_do_not_step_at_is_refused(tmp_path: Path, rate: str) -> None:
    with pytest.raises(InputError, match=rf"^{tmp_path}/r.trc: header says DataRate {float(rate):g} but the Time "
                                         r"column steps 0.0166667 s \(60 frames per second\); correct one of them$"):
        read_labeled(_with_rate(tmp_path / "r.trc", rate))


@pytest.mark.parametrize("rows", [2, 30])
def test_a_data_rate_within_the_times_printing_is_read(tmp_path: Path, rows: int) -> None:
    assert read_labeled(_with_rate(tmp_path / "r.trc", "60.00", rows)).rate == 60.0


def test_one_row_has_no_step_to_disagree_with(tmp_path: Path) -> None:
    assert read_labeled(_with_rate(tmp_path / "r.trc", "120", rows=1)).rate == 120.0


@pytest.mark.parametrize("path", sorted(DATA.rglob("*.trc")), ids=lambda p: p.name)
def test_every_real_trc_agrees_with_its_times(path: Path) -> None:
    assert read_labeled(path).rate > 0
