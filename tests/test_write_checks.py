"""``write_labeled`` refuses, in one line, labels its readers would refuse or that it could not
write: names for 3 markers over positions of 41 gave a numpy broadcast ValueError for a .c3d
and a .trc its own reader refused ("114 values past the 3 named markers"), and labels of no
marker, or of one frame for a .csv, were written where nothing reads them back."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories
from tests.test_formats import _occluded_cmu

SUFFIXES = [".c3d", ".trc", ".csv"]


def _three_names(t: LabeledTrajectories) -> LabeledTrajectories:
    return replace(t, names=t.names[:3])


def _occluded_of_other_shape(t: LabeledTrajectories) -> LabeledTrajectories:
    return replace(t, occluded=t.occluded[:, :-1])


def _confidence_of_other_shape(t: LabeledTrajectories) -> LabeledTrajectories:
    return replace(t, confidence=np.ones((t.n_frames + 1, len(t.names))))


def _flat_positions(t: LabeledTrajectories) -> LabeledTrajectories:
    return replace(t, positions=t.positions.reshape(t.n_frames, -1))


def _no_marker(t: LabeledTrajectories) -> LabeledTrajectories:
    return LabeledTrajectories([], t.positions[:, :0], t.occluded[:, :0], t.rate)


def _no_rate(t: LabeledTrajectories) -> LabeledTrajectories:
    return replace(t, rate=0.0)


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize(("broken", "message"), [
    (_three_names, r"names must be one string per marker of positions \(4, 41, 3\); got 3 names"),
    (_occluded_of_other_shape, r"occluded must be \(frames, markers\) = \(4, 41\) as positions, got \(4, 40\)"),
    (_confidence_of_other_shape, r"confidence must be \(frames, markers\) = \(4, 41\) as positions, got \(5, 41\)"),
    (_flat_positions, r"positions must be \(frames, markers, 3\), got shape \(4, 123\)"),
    (_no_marker, r"nothing to write that reads back: 0 markers x 4 frames"),
    (_no_rate, r"frame rate must be a positive number, got 0.0"),
])
def test_labels_that_do_not_hold_together_are_refused(
    tmp_path: Path, suffix: str, broken: Callable[[LabeledTrajectories], LabeledTrajectories], message: str
) -> None:
    out = tmp_path / f"out{suffix}"
    with pytest.raises(InputError, match=rf"^{out}: {message}"):
        write_labeled(out, broken(_occluded_cmu(frames=4)))
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_one_frame_is_written_where_its_reader_reads_it_back(tmp_path: Path, suffix: str) -> None:
    one = _occluded_cmu(frames=2)
    one = LabeledTrajectories(one.names, one.positions[1:], one.occluded[1:], one.rate)
    out = tmp_path / f"out{suffix}"
    if suffix == ".csv":  # its rate is read from the times: one row gives none
        with pytest.raises(InputError, match=rf"^{out}: nothing to write that reads back: 41 markers x 1 frames "
                                             r"\(a .csv needs a marker and 2 frames\)"):
            write_labeled(out, one)
        return
    write_labeled(out, one)
    assert read_labeled(out).n_frames == 1


@pytest.mark.parametrize(
    "name", ["missing_dir/out.c3d", "missing_dir/out.csv", "out.txt"], ids=str
)
def test_unwritable_output_raises_input_error(name: str, tmp_path: Path) -> None:
    with pytest.raises(InputError, match=Path(name).name.replace(".", r"\.")):
        write_labeled(tmp_path / name, _occluded_cmu(frames=3))


def test_a_name_with_a_tab_is_refused_for_trc_and_csv_and_kept_by_c3d(tmp_path: Path) -> None:
    """A tab in a name made a TRC no reader parses back ("line 4 names 5 markers"); a CSV holds
    it, but its reader refuses control characters in names (as the capture JSON does), so it
    is not written either."""
    traj = _occluded_cmu(frames=3)
    traj.names[0] = "Male:\tLFWT"
    with pytest.raises(InputError, match="tab or line break"):
        write_labeled(tmp_path / "x.trc", traj)
    assert not (tmp_path / "x.trc").exists()
    with pytest.raises(InputError, match=r"x.csv: marker name 'Male:\\tLFWT' has a control character"):
        write_labeled(tmp_path / "x.csv", traj)
    assert not (tmp_path / "x.csv").exists()
    write_labeled(tmp_path / "x.c3d", traj)
    assert read_labeled(tmp_path / "x.c3d").names == traj.names
