"""Wide CSV tables of labeled trajectories: one row per frame, x/y/z columns per marker."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from service.errors import InputError
from service.io.formats.conventions import hidden_samples, require_file, sample_cells
from service.io.recording import LabeledTrajectories, SourceFile

_AXES = ("x", "y", "z")


def write_csv(path: str | Path, traj: LabeledTrajectories, source: SourceFile | None = None, start: int = 0) -> None:
    """Write ``frame,time,<name>_x,<name>_y,<name>_z,...`` in mm; occluded cells empty.

    ``frame`` numbers the input's frames as its file does (the labels of input frame
    ``start`` are frame ``source.first_frame + start``); ``time`` is seconds since the
    input's first frame. Always mm: the table has no unit of its own.

    Raises:
        InputError: the path cannot be written.
    """
    path = Path(path)
    first = (source or SourceFile()).first_frame + start
    hidden = hidden_samples(traj)
    header = ["frame", "time"] + [f"{name}_{axis}" for name in traj.names for axis in _AXES]
    try:
        with path.open("w", newline="", encoding="utf-8") as f:
            writer = csv.writer(f)
            writer.writerow(header)
            writer.writerows(
                [str(first + f), repr((start + f) / traj.rate)] + sample_cells(traj.positions[f], hidden[f])
                for f in range(traj.n_frames)
            )
    except OSError as exc:
        raise InputError(f"{path}: cannot write ({exc.strerror})") from exc


def read_csv_labeled(path: str | Path) -> LabeledTrajectories:
    """Read a table written by :func:`write_csv`; the rate comes from the time column.

    Raises:
        InputError: missing file, bad header, a non-numeric cell, a ragged row, or fewer
            than two frames (no rate to infer).
    """
    path = require_file(path)
    try:
        # utf-8-sig: spreadsheets often save with a byte-order mark.
        with path.open(newline="", encoding="utf-8-sig", errors="replace") as f:
            rows = list(csv.reader(f))
    except csv.Error as exc:
        raise InputError(f"{path}: not a CSV table ({exc})") from exc
    names = _names(rows[0] if rows else [], path)
    width = 2 + 3 * len(names)
    table = np.array([_floats(row, width, path, i) for i, row in enumerate(rows[1:], start=2)])
    if len(table) < 2:
        raise InputError(f"{path}: needs at least two frames to infer the frame rate")
    positions = table[:, 2:].reshape(len(table), len(names), 3)
    occluded = np.isnan(positions).any(axis=2)
    positions[occluded] = np.nan
    return LabeledTrajectories(names, positions, occluded, _rate(table[:, 0], table[:, 1], path))


def _names(header: list[str], path: Path) -> list[str]:
    triples = [header[i : i + 3] for i in range(2, len(header), 3)]
    names = [t[0][:-2] for t in triples]
    expected = ["frame", "time"] + [f"{n}_{axis}" for n in names for axis in _AXES]
    if header != expected or not names:
        raise InputError(f"{path}: header should be frame,time,<name>_x,<name>_y,<name>_z,...")
    return names


def _floats(row: list[str], width: int, path: Path, line: int) -> list[float]:
    if len(row) != width:
        raise InputError(f"{path}:{line}: {len(row)} cells, header has {width}")
    try:
        return [float(cell) if cell.strip() else np.nan for cell in row]
    except ValueError as exc:
        raise InputError(f"{path}:{line}: {exc}") from None


def _rate(frames: np.ndarray, times: np.ndarray, path: Path) -> float:
    span = times[-1] - times[0]
    rate = (frames[-1] - frames[0]) / span if span > 0 else np.nan
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"{path}: frame and time columns give no positive frame rate")
    return float(rate)
