"""TRC files: the tab-separated marker tables of OpenSim and Pose2Sim, read and written.

Parsed by hand: the one TRC reader on PyPI (trc-data-reader) is a small package we have
not vetted and would rather not depend on, and the format is a plain tab-separated table.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from service.errors import InputError
from service.io.formats.conventions import (
    SCALED_DIGITS,
    check_rows,
    from_millimetres,
    hidden_samples,
    printed_step,
    rate_of_times,
    read_text,
    require_file,
    require_names,
    require_samples,
    sample_cells,
    to_millimetres,
    zero_gaps_to_nan,
)
from service.io.formats.replace_file import replacing
from service.io.recording import LabeledTrajectories, Recording, SourceFile

_KEYS = ("DataRate", "NumFrames", "NumMarkers", "Units")
_FIRST_DATA_LINE = 6  # after the magic line, the key/value lines, names, X1 Y1 Z1


def read_trc(path: str | Path, max_markers: int | None = None, max_frames: int | None = None) -> Recording:
    """Read a TRC file into millimetres; blank cells and (0, 0, 0) samples become NaN.

    NumMarkers and NumFrames are checked against ``max_markers``/``max_frames`` (if given)
    before any row is read.

    Raises:
        InputError: missing or malformed file (header, a NumMarkers other than the names
            on line 4, a non-numeric cell, a row count other than NumFrames, rows out of
            order), zero frames, an unknown unit, more markers or frames than allowed, a
            name no output carries back (``require_names``: a control character, over 255
            bytes), or a name twice or an infinite or absurd coordinate (``require_samples``).
    """
    path = require_file(path)
    lines = read_text(path).splitlines()
    if not lines or not lines[0].startswith("PathFileType"):
        raise InputError(f"{path}: not a TRC file (no PathFileType header)")
    if len(lines) < _FIRST_DATA_LINE - 1:
        raise InputError(f"{path}: TRC file ends inside its header")
    header = _header(lines, path)
    n_markers = _count(header, "NumMarkers", path)
    declared = _count(header, "NumFrames", path)
    _at_most(n_markers, "markers", max_markers, "max_markers", path)
    _at_most(declared, "frames", max_frames, "max_frames", path)
    names = _names(lines[3], n_markers, path)
    require_names(names, path)
    numbered = [
        (f"{path}:{number}", line)
        for number, line in enumerate(lines[_FIRST_DATA_LINE - 1 :], start=_FIRST_DATA_LINE)
        if line.strip()
    ]
    if len(numbered) != declared:
        raise InputError(f"{path}: header says NumFrames {declared} but has {len(numbered)} rows")
    if not numbered:
        raise InputError(f"{path}: TRC file has zero frames")
    cells = _frame_cells(numbered)
    check_rows(cells[:, 0], cells[:, 1], [where for where, _ in numbered])
    rows = [_row(line, n_markers, where) for where, line in numbered]
    positions = np.array(rows).reshape(len(rows), n_markers, 3)
    positions = to_millimetres(positions, header["Units"], path)
    require_samples(names, positions, path)
    source = SourceFile.of_table(header["Units"].strip().lower(), cells[:, 0], cells[:, 1])
    rate = _number(header, "DataRate", path)
    _check_rate(rate, cells[:, 1], path)
    return Recording(names, zero_gaps_to_nan(positions), rate, source)


def write_trc(path: str | Path, traj: LabeledTrajectories, source: SourceFile | None = None, start: int = 0) -> None:
    """Write ``traj`` as a TRC table in ``source.unit`` (mm without a source); occluded cells empty.

    ``Frame#`` and ``Time`` are the input's (``SourceFile.numbering``): a table's own, else
    counted from 1 at the input's first frame, so the labels of input frame ``start`` are
    numbered ``source.first_frame + start + 1``.

    Raises:
        InputError: a marker name with a tab or line break (no TRC can hold it), or the path
            cannot be written.
    """
    path = Path(path)
    check_trc_names(traj.names, path)
    source = source or SourceFile()
    numbering = source.numbering(start, traj.n_frames, traj.rate)
    first = numbering[0][0] if numbering else str(source.first_frame + start + 1)
    names = "\t".join(f"{name}\t\t" for name in traj.names)
    axes = "\t".join(f"X{i}\tY{i}\tZ{i}" for i in range(1, len(traj.names) + 1))
    header = [
        f"PathFileType\t4\t(X/Y/Z)\t{path.name}",
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames",
        f"{traj.rate!r}\t{traj.rate!r}\t{traj.n_frames}\t{len(traj.names)}\t{source.unit}\t{traj.rate!r}\t{first}\t"
        f"{traj.n_frames}",
        f"Frame#\tTime\t{names}",
        f"\t\t{axes}",
        "",
    ]
    values = from_millimetres(traj.positions, source.unit)
    digits = None if source.unit.strip().lower() == "mm" else SCALED_DIGITS  # mm: as given, exactly
    hidden = hidden_samples(traj)
    rows = [
        "\t".join(list(numbering[f]) + sample_cells(values[f], hidden[f], digits)) for f in range(traj.n_frames)
    ]
    with replacing(path) as temp:
        temp.write_text("\n".join(header + rows) + "\n", encoding="utf-8")



def check_trc_names(names: list[str], path: str | Path) -> None:
    """A TRC separates its cells by tabs and its rows by line breaks: a name holding either
    would write a table no reader parses back.

    Raises:
        InputError: the first such name.
    """
    for name in names:
        if re.search(r"[\t\r\n]", name):
            raise InputError(f"{path}: marker name {name!r} holds a tab or line break, which a TRC cannot; "
                             "write .c3d")  # a .csv would hold it, but its reader refuses control characters


def _at_most(count: int, what: str, limit: int | None, name: str, path: Path) -> None:
    if limit is not None and count > limit:
        raise InputError(f"{path}: {count} {what} exceeds the limit of {limit} (limits.{name})")


def _header(lines: list[str], path: Path) -> dict[str, str]:
    """Line 3 holds the values of the keys named on line 2."""
    keys = [k.strip() for k in lines[1].split("\t")]
    values = [v.strip() for v in lines[2].split("\t")]
    header = dict(zip(keys, values, strict=False))
    missing = [k for k in _KEYS if not header.get(k)]
    if missing:
        raise InputError(f"{path}: TRC header lacks {', '.join(missing)}")
    if "X1" not in lines[4].split("\t"):
        raise InputError(f"{path}: line 5 should hold the X1 Y1 Z1 column names")
    return header


def _number(header: dict[str, str], key: str, path: Path) -> float:
    try:
        value = float(header[key])
    except ValueError:
        raise InputError(f"{path}: TRC header {key} is {header[key]!r}, not a number") from None
    if not np.isfinite(value):
        raise InputError(f"{path}: TRC header {key} is {header[key]!r}, not a finite number")
    if not value > 0 and key != "NumFrames":
        raise InputError(f"{path}: TRC header {key} must be positive, got {header[key]}")
    return value


def _check_rate(rate: float, times: np.ndarray, path: Path) -> None:
    """DataRate agrees with the Time column, within how the times were printed. A header that
    disagrees with its rows is refused, as for NumFrames: labeled at DataRate 120 a take whose
    times step 1/60 s was labeled, and written back, at the wrong speed, without a word."""
    if len(times) < 2:
        return
    span = float(times[-1] - times[0])  # > 0: check_rows
    from_times = (len(times) - 1) / span
    if abs(from_times - rate) > from_times**2 * printed_step(times) / span + 1e-6 * rate:
        said = rate_of_times(times, path)
        raise InputError(f"{path}: header says DataRate {rate:g} but the Time column steps {1 / said:.6g} s "
                         f"({said:g} frames per second); correct one of them")


def _count(header: dict[str, str], key: str, path: Path) -> int:
    """NumMarkers or NumFrames: a whole number (2.5 markers is a broken header, not 2)."""
    value = _number(header, key, path)
    if not value.is_integer():
        raise InputError(f"{path}: TRC header {key} is {header[key]!r}, not a whole number")
    return int(value)


def _names(line: str, n_markers: int, path: Path) -> list[str]:
    """One name per marker after Frame# and Time, then two blank cells (its Y and Z).

    Exactly NumMarkers of them, as OpenSim's TRCFileAdapter requires: a header that
    disagrees with the names leaves no telling which is right, and reading only the
    first NumMarkers columns dropped the rest silently.
    """
    names = [name.strip() for name in line.split("\t")[2::3]]
    while names and not names[-1]:
        names.pop()
    if len(names) != n_markers or not all(names):
        raise InputError(f"{path}: line 4 names {len(names)} markers but the header says NumMarkers {n_markers}"
                         if len(names) != n_markers and all(names) else
                         f"{path}: line 4 should name {n_markers} markers (NumMarkers)")
    return names


def _frame_cells(numbered: list[tuple[str, str]]) -> np.ndarray:
    """``(rows, 2)`` each row's Frame# and Time (their order: ``check_rows``).

    Rows out of order are refused rather than sorted: they are a broken export (a row whose
    positions are another frame's), and a sorted table would hide that its output's frames
    are not the input's rows; OpenSim requires Time to increase too.
    """
    cells = []
    for where, line in numbered:
        first = line.split("\t")[:2]
        try:
            cells.append((float(first[0]), float(first[1] if len(first) > 1 else "")))
        except ValueError:
            raise InputError(f"{where}: a row should start with its Frame# and Time, got {first}") from None
    return np.array(cells)


def _row(line: str, n_markers: int, where: str) -> list[float]:
    """The X Y Z cells of one frame; exporters may drop trailing blank cells, or add some.

    Values past the named markers' columns are refused: they are samples of a marker the
    header does not name, and would be dropped without a word."""
    split = line.split("\t")
    cells, extra = split[2 : 2 + 3 * n_markers], [cell for cell in split[2 + 3 * n_markers :] if cell.strip()]
    if extra:
        raise InputError(f"{where}: {len(extra)} values past the {n_markers} named markers' columns (a marker "
                         "without a name in the header?)")
    cells += [""] * (3 * n_markers - len(cells))
    try:
        return [float(cell) if cell.strip() else np.nan for cell in cells]
    except ValueError as exc:
        raise InputError(f"{where}: {exc}") from None
