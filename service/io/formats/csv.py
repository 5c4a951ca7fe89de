"""Wide CSV tables of labeled trajectories: one row per frame, x/y/z columns per marker."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from service.errors import InputError
from service.io.formats.conventions import (
    check_rows,
    hidden_samples,
    rate_of_times,
    read_text,
    require_file,
    require_names,
    require_samples,
    sample_cells,
)
from service.io.formats.replace_file import replacing
from service.io.recording import LabeledTrajectories, Recording, SourceFile

_AXES = ("x", "y", "z")
_CONFIDENCE = "_confidence"


def write_csv(path: str | Path, traj: LabeledTrajectories, source: SourceFile | None = None, start: int = 0) -> None:
    """Write ``frame,time,<name>_x,<name>_y,<name>_z,...`` in mm; occluded cells empty.

    Camera mode adds ``<name>_best_view,...`` after the coordinates: the name of the
    camera that shows each marker best in that frame (``LabeledTrajectories.best_view``),
    empty where the marker has no position.
    Labels with confidences end with ``<name>_confidence,...``: the probability that the
    marker's label is right, in every frame (occluded ones too: that it is occluded
    there), empty where no window said.

    ``frame`` and ``time`` are the input's (``SourceFile.numbering``): a table's own, else
    counted from 1 at its first frame, as a C3D's header and a TRC's ``Frame#`` do (the
    labels of input frame ``start`` are frame ``source.first_frame + start + 1``). Always
    mm: the table has no unit of its own.

    Raises:
        InputError: the path cannot be written.
    """
    path = Path(path)
    source = source or SourceFile()
    numbering = source.numbering(start, traj.n_frames, traj.rate)
    hidden = hidden_samples(traj)
    header = ["frame", "time"] + [f"{name}_{axis}" for name in traj.names for axis in _AXES]
    views = traj.best_view_names()
    header += [f"{name}_best_view" for name in traj.names] if views is not None else []
    confidence = traj.confidence.size > 0
    header += [f"{name}{_CONFIDENCE}" for name in traj.names] if confidence else []
    with replacing(path) as temp, temp.open("w", newline="", encoding="utf-8") as table:
        writer = csv.writer(table)
        writer.writerow(header)
        writer.writerows(
            list(numbering[f]) + sample_cells(traj.positions[f], hidden[f])
            + ([v or "" for v in views[f]] if views is not None else [])
            + (_confidence_cells(traj.confidence[f]) if confidence else [])
            for f in range(traj.n_frames)
        )


def read_csv(path: str | Path) -> Recording:
    """A table ``write_csv`` wrote, as a recording to relabel: its frame numbers and times
    kept (``SourceFile``), in mm.

    Raises:
        InputError: as ``read_csv_labeled``.
    """
    labels, source = _read_table(path)
    return Recording(labels.names, labels.positions, labels.rate, source)


def read_csv_labeled(path: str | Path) -> LabeledTrajectories:
    """Read a table written by :func:`write_csv`; the rate comes from the time column.

    Raises:
        InputError: missing file, bad header, a non-numeric cell, a ragged row, fewer
            than two frames (no rate to infer), or a name twice or an infinite or absurd
            coordinate (``require_samples``).
    """
    return _read_table(path)[0]


def _read_table(path: str | Path) -> tuple[LabeledTrajectories, SourceFile]:
    """The labels of a ``write_csv`` table, and its numbering (first frame less 1, first time)."""
    path = require_file(path)
    lines, rows = _rows(path)
    rows, confidence = _split_confidence(rows, lines, path)
    names, with_views = _names(rows[0] if rows else [], path)
    require_names(names, path)
    width = 2 + 3 * len(names)
    views = [_view_cells(row, width, len(names), path, i) for i, row in zip(lines[1:], rows[1:])] if with_views else []
    table = np.array([_floats(row[:width] if with_views else row, width, path, i) for i, row in zip(lines[1:], rows[1:])])
    if len(table) < 2:
        raise InputError(f"{path}: needs at least two frames to infer the frame rate")
    check_rows(table[:, 0], table[:, 1], [f"{path}:{line}" for line in lines[1:]])
    positions = table[:, 2:].reshape(len(table), len(names), 3)
    require_samples(names, positions, path)
    occluded = np.isnan(positions).any(axis=2)
    positions[occluded] = np.nan
    labels = LabeledTrajectories(names, positions, occluded, rate_of_times(table[:, 1], path))
    source = SourceFile.of_table("mm", table[:, 0], table[:, 1])
    if confidence is not None:
        labels.confidence = _named_confidence(confidence, names, path)
    if not with_views:
        return labels, source
    view_names = list(dict.fromkeys(name for row in views for name in row if name))
    best_view = np.array([[view_names.index(name) if name else -1 for name in row] for row in views], dtype=int)
    return LabeledTrajectories(names, positions, occluded, labels.rate, best_view=best_view, view_names=view_names,
                               confidence=labels.confidence), source


def _rows(path: Path) -> tuple[list[int], list[list[str]]]:
    """The table's rows and the line each ends on, blank lines left out as a TRC's are (an
    editor's trailing or separating empty line is no frame).

    Raises:
        InputError: not CSV, or cells separated by ';' (a spreadsheet in a comma-decimal locale).
    """
    lines, rows = [], []
    reader = csv.reader(io.StringIO(read_text(path), newline=""))
    try:
        for row in reader:
            if any(cell.strip() for cell in row):
                lines.append(reader.line_num)
                rows.append(row)
    except csv.Error as exc:
        raise InputError(f"{path}: not a CSV table ({exc})") from exc
    if rows and len(rows[0]) == 1 and ";" in rows[0][0]:
        raise InputError(f"{path}:{lines[0]}: the cells are separated by ';'; a markerflow CSV separates them by ',' "
                         "(save it with ',' as the separator and '.' as the decimal point)")
    return lines, rows


def _split_confidence(
    rows: list[list[str]], lines: list[int], path: Path
) -> tuple[list[list[str]], tuple[list[str], np.ndarray] | None]:
    """The table without its trailing ``<name>_confidence`` columns, and those columns'
    names and values (None when there are none)."""
    header = rows[0] if rows else []
    count = next((i for i, cell in enumerate(reversed(header)) if not cell.endswith(_CONFIDENCE)), len(header))
    if count == 0:
        return rows, None
    cut = len(header) - count
    for line, row in zip(lines[1:], rows[1:]):
        if len(row) != len(header):
            raise InputError(f"{path}:{line}: {len(row)} cells, header has {len(header)}")
    values = np.array([_floats(row[cut:], count, path, i) for i, row in zip(lines[1:], rows[1:])]).reshape(-1, count)
    return [row[:cut] for row in rows], ([cell[: -len(_CONFIDENCE)] for cell in header[cut:]], values)


def _named_confidence(confidence: tuple[list[str], np.ndarray], names: list[str], path: Path) -> np.ndarray:
    if confidence[0] != names:
        raise InputError(f"{path}: confidence columns should be <name>_confidence for each marker, in order")
    return confidence[1]


def _confidence_cells(values: np.ndarray) -> list[str]:
    return ["" if np.isnan(v) else repr(float(v)) for v in values]


def _names(header: list[str], path: Path) -> tuple[list[str], bool]:
    """The marker names, and whether ``<name>_best_view`` columns follow the coordinates."""
    n_markers = (len(header) - 2) // 4 if header[-1:] and header[-1].endswith("_best_view") else (len(header) - 2) // 3
    names = [header[i][:-2] for i in range(2, 2 + 3 * n_markers, 3)]
    expected = ["frame", "time"] + [f"{n}_{axis}" for n in names for axis in _AXES]
    with_views = expected + [f"{n}_best_view" for n in names]
    if header not in (expected, with_views) or not names:
        raise InputError(f"{path}: header should be frame,time,<name>_x,<name>_y,<name>_z,...[,<name>_best_view,...]")
    return names, header == with_views


def _view_cells(row: list[str], width: int, n_markers: int, path: Path, line: int) -> list[str]:
    if len(row) != width + n_markers:
        raise InputError(f"{path}:{line}: {len(row)} cells, header has {width + n_markers} (a best view in each)")
    return row[width:]


def _floats(row: list[str], width: int, path: Path, line: int) -> list[float]:
    if len(row) != width:
        raise InputError(f"{path}:{line}: {len(row)} cells, header has {width}")
    try:
        return [float(cell) if cell.strip() else np.nan for cell in row]
    except ValueError as exc:
        raise InputError(f"{path}:{line}: {exc}") from None
