"""markerflow's sample conventions at the file boundary: millimetres, NaN for gaps."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from service.errors import InputError
from service.io.marker_names import first_name_problem, shown
from service.io.recording import LabeledTrajectories

MM_PER_UNIT = {"mm": 1.0, "cm": 10.0, "m": 1000.0}
# As the HTTP service's documents (``service.capture.document``): no capture spans 1000 km,
# and sums of squares of larger coordinates overflow to inf inside the geometry.
MAX_MM = 1e9


def require_file(path: str | Path) -> Path:
    """Return ``path`` as a Path, or raise InputError if it is not an existing file."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if not path.is_file():
        raise InputError(f"{path}: not a regular file")
    return path


# Lab PCs export tables in UTF-8 (spreadsheets with a byte-order mark) or in Windows' own
# code page; a name decoded wrongly would be written wrongly, so nothing is replaced.
TEXT_ENCODINGS = ("utf-8-sig", "cp1252")


def read_text(path: Path) -> str:
    """The text of table file ``path``, in the first of ``TEXT_ENCODINGS`` that decodes it whole.

    Raises:
        InputError: it cannot be read, or is text in neither (a binary file, another code page).
    """
    try:
        data = path.read_bytes()
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    for encoding in TEXT_ENCODINGS:
        try:
            return data.decode(encoding)
        except UnicodeDecodeError:
            continue
    raise InputError(f"{path}: not text in UTF-8 or Windows-1252 (save it as UTF-8)")


# A row's time step may differ from the median step by this share: a dropped frame doubles
# it (+100 %), where times printed to 3 decimals at 240 Hz step 0.004 or 0.005 s (+25 %).
EVEN_STEP = 0.5


def check_rows(numbers: np.ndarray, times: np.ndarray, lines: list[str]) -> None:
    """A table's rows go forward in frame number and time, evenly spaced in time.

    Frame numbers may skip (a decimated take numbers every other frame) and are written
    back as they were; but the labeler takes rows as evenly spaced, so a gap in time (a
    dropped frame) or a repeated row is refused rather than labeled at the wrong speed.
    ``lines``: where each row is, for the message (``path:line``).
    """
    steps, ticks = np.diff(numbers), np.diff(times)
    back = np.flatnonzero(~((steps > 0) & (ticks > 0)))
    if len(back):
        row = int(back[0]) + 1
        raise InputError(f"{lines[row]}: frame {numbers[row]:g} at time {times[row]:g} does not follow frame "
                         f"{numbers[row - 1]:g} at time {times[row - 1]:g}; rows must be in order")
    if len(ticks):
        usual = float(np.median(ticks))
        uneven = np.flatnonzero(np.abs(ticks - usual) > EVEN_STEP * usual)
        if len(uneven):
            row = int(uneven[0]) + 1
            raise InputError(f"{lines[row]}: time {times[row]:g} is {ticks[row - 1]:g} s after the row before, the "
                             f"rows' step is {usual:g} s; rows must be evenly spaced in time (a frame without "
                             "samples is a row of empty cells)")


def rate_of_times(times: np.ndarray, path: Path) -> float:
    """Rows per second: the labeler steps row by row (``check_rows``: evenly in time), so a
    decimated table's frame numbers, which skip, do not give its rate."""
    span = times[-1] - times[0]
    rate = (len(times) - 1) / span if span > 0 else np.nan
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"{path}: the time column gives no positive frame rate")
    # times printed to d decimals put the rate within rate^2 10^-d / span of the true one
    # (120 Hz at 3 decimals over 124 rows reads 119.96): the shortest rate that close is it
    close = rate**2 * printed_step(times) / span
    shortest = next((round(rate, q) for q in range(7) if abs(rate - round(rate, q)) <= close), rate)
    return float(f"{shortest:.9g}")  # the times' rounding off: 100 Hz, not 99.99999999999999


def printed_step(times: np.ndarray) -> float:
    """The resolution the times were printed at: 10^-d for the fewest decimals d that hold them all."""
    for decimals in range(10):
        scaled = times * 10.0**decimals
        if np.all(np.abs(scaled - np.round(scaled)) < 1e-6 * np.maximum(1.0, np.abs(scaled))):
            return 10.0**-decimals
    return 0.0


def to_millimetres(values: np.ndarray, unit: str, path: Path) -> np.ndarray:
    """Scale lengths given in ``unit`` (mm, cm or m; case and spaces ignored) to mm.

    Raises:
        InputError: the unit is not one of the above.
    """
    scale = MM_PER_UNIT.get(unit.strip().lower())
    if scale is None:
        raise InputError(f"{path}: unsupported length unit {unit!r} (expected mm, cm or m)")
    return np.asarray(values, dtype=float) * scale


def require_samples(names: list[str], positions: np.ndarray, path: Path) -> None:
    """Refuse what no labeling can answer for: a marker name twice (which column is it?), or
    a coordinate that is +-inf or beyond ``MAX_MM`` (an overflow, not a gap).

    A gap is written blank, NaN or (0, 0, 0), and those stay gaps; an infinite or absurd
    number is a broken export, refused like a non-numeric cell, with the marker and frame
    (counted from 0, as ``--start``) so it can be found. The HTTP service refuses both too.

    Raises:
        InputError: the first duplicate name, or the first such coordinate.
    """
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise InputError(f"{path}: marker name {name!r} appears twice")
        seen.add(name)
    bad = np.argwhere(~(np.abs(positions) <= MAX_MM) & ~np.isnan(positions))
    if len(bad):
        frame, marker, axis = (int(i) for i in bad[0])
        value = float(positions[frame, marker, axis])
        why = "" if np.isinf(value) else f", beyond the {MAX_MM:.0e} mm any capture fits in"
        raise InputError(f"{path}: marker {names[marker]!r} has {'xyz'[axis]} = {value:.3g} mm in frame {frame}{why}")


def require_names(names: list[str], path: Path) -> None:
    """Refuse a name no output carries back as itself (``name_problem``: a NUL came back from
    a C3D cut out, a name over 255 bytes made a C3D no reader opens), as the capture JSON does.

    Raises:
        InputError: the first such name.
    """
    found = first_name_problem(names)
    if found is not None:
        raise InputError(f"{path}: marker name {shown(found[0])} {found[1]}")


def check_labels(traj: LabeledTrajectories, path: Path, least_frames: int) -> None:
    """Refuse labels a file of them would not hold, or hold so that its reader refuses it:
    arrays of other shapes than the names and positions say (a numpy broadcast error for a
    .c3d, a .trc of "values past the named markers"), no marker, fewer than ``least_frames``
    frames, or no positive frame rate.

    Raises:
        InputError: one line, naming ``path``.
    """
    positions = np.asarray(traj.positions)
    if positions.ndim != 3 or positions.shape[2] != 3:
        raise InputError(f"{path}: positions must be (frames, markers, 3), got shape {positions.shape}")
    frames, markers = positions.shape[:2]
    if not all(isinstance(name, str) for name in traj.names) or len(traj.names) != markers:
        raise InputError(f"{path}: names must be one string per marker of positions {positions.shape}; got "
                         f"{len(traj.names)} names")
    arrays = [("occluded", traj.occluded, (frames, markers)), ("confidence", traj.confidence, (frames, markers))]
    arrays += [("best_view", traj.best_view, (frames, markers))] if traj.view_names else []
    for what, array, shape in arrays:
        if np.shape(array) != shape and (what == "occluded" or np.size(array)):
            raise InputError(f"{path}: {what} must be (frames, markers) = {shape} as positions, got {np.shape(array)}")
    if np.size(traj.unlabeled) and (np.ndim(traj.unlabeled) != 3 or np.shape(traj.unlabeled)[::2] != (frames, 3)):
        raise InputError(f"{path}: unlabeled must be ({frames}, channels, 3) as positions, got {np.shape(traj.unlabeled)}")
    if not markers or frames < least_frames:
        raise InputError(f"{path}: nothing to write that reads back: {markers} markers x {frames} frames (a "
                         f"{path.suffix.lower()} needs a marker and {least_frames} frame{'s' * (least_frames > 1)})")
    if not (np.isfinite(traj.rate) and traj.rate > 0):
        raise InputError(f"{path}: frame rate must be a positive number, got {traj.rate!r}")


def from_millimetres(values: np.ndarray, unit: str) -> np.ndarray:
    """Millimetres in ``unit`` (one ``to_millimetres`` accepts): the inverse scaling."""
    return np.asarray(values, dtype=float) / MM_PER_UNIT[unit.strip().lower()]


def zero_gaps_to_nan(positions: np.ndarray) -> np.ndarray:
    """Copy of ``(frames, markers, 3)`` positions with exact (0, 0, 0) samples set to NaN.

    Some exporters (e.g. QTM, OpenSim examples) write a missing sample as the origin.
    """
    out = np.array(positions, dtype=float)
    out[(out == 0).all(axis=2)] = np.nan
    return out


def hidden_samples(traj: LabeledTrajectories) -> np.ndarray:
    """``(frames, markers)`` bool: samples to write as missing (occluded, or NaN position)."""
    return np.asarray(traj.occluded, dtype=bool) | np.isnan(traj.positions).any(axis=2)


# Significant digits of a coordinate written in a unit other than mm: scaling to mm and back
# leaves float noise in the last bits (0.1044258 m was written 0.10442580000000001). Three
# roundings put it within 2 units in the last place, under half a step of the 15th digit, so
# 15 digits give back any value of up to 15 the input had, and any other within 5e-15.
SCALED_DIGITS = 15


def sample_cells(xyz: np.ndarray, hidden: np.ndarray, digits: int | None = None) -> list[str]:
    """One frame's x, y, z text cells per marker, blank where hidden.

    ``repr`` of a float (``digits`` None) round-trips exactly: a table read back gives the
    values written; else each value to ``digits`` significant digits.
    """
    cells: list[str] = []
    for sample, gone in zip(xyz, hidden, strict=True):
        cells += [""] * 3 if gone else [repr(float(v)) if digits is None else f"{float(v):.{digits}g}" for v in sample]
    return cells


def without_samples(unlabeled: np.ndarray, samples: np.ndarray, tolerance: float) -> np.ndarray:
    """``unlabeled`` ``(frames, U, 3)`` without each sample within ``tolerance`` of one of
    ``samples`` ``(frames, K, 3)`` (NaN where absent) in its frame, and without the channels
    that leaves empty: a sample an output holds under a name is not written again as ``*N``."""
    if not unlabeled.size or not samples.shape[1]:
        return unlabeled
    gap = np.linalg.norm(unlabeled[:, :, None] - samples[:, None], axis=3)  # (frames, U, K)
    again = (np.nan_to_num(gap, nan=np.inf) < tolerance).any(axis=2)
    unlabeled = np.where(again[..., None], np.nan, unlabeled)
    return unlabeled[:, np.isfinite(unlabeled).all(axis=2).any(axis=0)]
