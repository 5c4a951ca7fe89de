"""Read and write marker files, choosing the format by file suffix."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from service.errors import InputError
from service.io.formats.c3d import point_labels, read_c3d, write_c3d
from service.io.formats.c3d_parameters import check_frame_numbers
from service.io.formats.conventions import check_labels, require_names
from service.io.formats.csv import read_csv, write_csv
from service.io.formats.trc import check_trc_names, read_trc, write_trc
from service.io.recording import LabeledTrajectories, Recording, SourceFile

_READERS = {".c3d": read_c3d, ".trc": read_trc, ".csv": read_csv}
_WRITERS = {".c3d": write_c3d, ".trc": write_trc, ".csv": write_csv}
_LEAST_FRAMES = {".csv": 2}  # a CSV's rate is read from its time column: one row gives none


def read_labeled(path: str | Path) -> Recording:
    """Read labeled trajectories from a .c3d, .trc or markerflow .csv file (millimetres, NaN gaps).

    The recording's ``source`` keeps what output written from it needs (unit, frame
    numbering and times, and a C3D's other content); a .csv is mm, as markerflow wrote it.

    Raises:
        InputError: unsupported suffix, or a missing or malformed file.
    """
    return _by_suffix(_READERS, path, "read")(path)


def write_labeled(
    path: str | Path, traj: LabeledTrajectories, source: SourceFile | None = None, start: int = 0
) -> None:
    """Write markerflow's labels to a .c3d, .trc or .csv file.

    Args:
        path: The output; its suffix picks the format.
        traj: The labels.
        source: The input's ``Recording.source``: a .c3d or .trc output is then written in
            the input's unit and frame numbering, and a .c3d from a C3D input is that file
            with only its points replaced (``write_c3d``). None: mm, frames from 0.
        start: The input frame of ``traj``'s first frame: a labeled span of a longer input
            (a C3D output still holds every input frame, unlabeled outside the span).

    Raises:
        InputError: unsupported suffix, labels whose arrays disagree with their names and
            positions or that the format's reader would refuse (``check_labels``,
            ``check_labels_fit``), labels that do not fit the source, or a path that cannot
            be written.
    """
    writer = _by_suffix(_WRITERS, path, "write")
    check_labels(traj, Path(path), _LEAST_FRAMES.get(Path(path).suffix.lower(), 1))
    check_labels_fit(path, list(traj.names), traj.n_frames, source, start)
    writer(path, traj, source, start)


def check_labels_fit(
    path: str | Path, names: list[str], n_frames: int, source: SourceFile | None = None, start: int = 0
) -> None:
    """Fail before labeling if labels of ``names`` over ``n_frames`` frames from input frame
    ``start`` cannot be written to ``path`` (as ``write_labeled``): a name a .trc or .csv
    cannot carry back (its reader refuses it), or, for a new .c3d, frame numbers past 65535
    (a table's own: a TRC whose Frame# starts at 70000 was refused after labeling).

    Raises:
        InputError: one line naming ``path``.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".trc":
        check_trc_names(names, path)
    if suffix in (".trc", ".csv"):
        require_names(names, path)
    if suffix == ".c3d" and not is_copy(path, source):  # a copy keeps the input's own numbers
        try:
            check_frame_numbers(max((source or SourceFile()).first_frame + start, 0), n_frames)
        except InputError as error:
            raise InputError(f"{path}: {error}") from None


def kept_source(source: SourceFile | None, names: list[str]) -> tuple[SourceFile | None, list[str]]:
    """What output of the labels ``names`` keeps of ``source``: all of it, unless it is a C3D
    without a point for some of them (a subject model's markers), whose labels cannot go into a
    copy of it: then its unit and numbering only; and those names."""
    if source is None or source.c3d is None:
        return source, []
    have = set(point_labels(source.c3d))
    lacking = [name for name in names if name not in have]
    return (replace(source, c3d=None) if lacking else source), lacking


def is_copy(path: str | Path, source: SourceFile | None) -> bool:
    """Output to ``path`` is a copy of the input C3D ``source`` (``write_c3d``), keeping what
    the labels do not replace."""
    return Path(path).suffix.lower() == ".c3d" and source is not None and source.c3d is not None


def check_output(path: str | Path, labeled: bool = True) -> None:
    """Fail early, before long work, if ``path`` cannot take labeled output; with ``labeled``
    False, any output file: a command writing a format of its own (a model's JSON, a MOT
    result, CHOICES.csv) checks its suffix itself, and the rest is the same.

    Raises:
        InputError: unsupported suffix, a folder that does not exist, or a folder as the path.
    """
    if Path(path).is_dir():  # first: a folder given with its trailing slash has no suffix either
        raise InputError(f"{path}: is a folder; name the output file")
    if labeled:
        _by_suffix(_WRITERS, path, "write")
    folder = Path(path).parent
    if not folder.is_dir():
        raise InputError(f"{path}: cannot write there, folder {folder} does not exist")


def _by_suffix(
    table: dict[str, Callable[..., Any]], path: str | Path, verb: str
) -> Callable[..., Any]:
    suffix = Path(path).suffix.lower()
    if suffix not in table:
        what = suffix or "a file without suffix"
        raise InputError(f"{path}: cannot {verb} {what}; use {', '.join(table)}")
    return table[suffix]
