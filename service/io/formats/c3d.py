"""C3D files: read labeled marker trajectories, write markerflow's labels."""

from __future__ import annotations

import re
import struct
from pathlib import Path

import ezc3d
import numpy as np

from service.errors import InputError
from service.io.formats.conventions import (
    hidden_samples,
    require_file,
    to_millimetres,
    zero_gaps_to_nan,
)
from service.io.recording import LabeledTrajectories, Recording

_BLOCK = 512  # C3D sections are addressed in 512-byte blocks
_MIPS = 86  # processor-type byte of the only big-endian C3D flavour


def read_c3d(path: str | Path) -> Recording:
    """Read the labeled 3D points of a C3D file, in millimetres.

    Missing samples (negative residual, or exactly (0, 0, 0)) become NaN.

    Raises:
        InputError: missing, unreadable or truncated file; no labeled points or a
            blank label; zero frames; no frame rate; a length unit other than mm, cm or m.
    """
    path = require_file(path)
    c3d = _load(path)
    points = c3d["data"]["points"][:3]  # (3, markers, frames)
    names = _labels(c3d, points.shape[1], path)
    _check_complete(c3d, path)
    if points.shape[2] == 0:
        raise InputError(f"{path}: C3D file has zero frames")
    rate = float(c3d["header"]["points"]["frame_rate"])
    if not rate > 0:
        raise InputError(f"{path}: C3D file has no point frame rate")
    units = list(c3d["parameters"]["POINT"].get("UNITS", {}).get("value", [])) or [""]
    positions = to_millimetres(points.transpose(2, 1, 0), units[0], path)
    return Recording(names, zero_gaps_to_nan(positions), rate)


def write_c3d(path: str | Path, traj: LabeledTrajectories) -> None:
    """Write ``traj`` as C3D points in mm; occluded samples get residual -1.

    Raises:
        InputError: nothing to write, or the path cannot be written.
    """
    path = Path(path)
    if traj.n_frames == 0 or not traj.names:
        raise InputError(f"{path}: nothing to write (zero frames or zero markers)")
    _check_writable(path)
    hidden = hidden_samples(traj)
    points = np.ones((4, len(traj.names), traj.n_frames))
    # (0, 0, 0) under residual -1: readers that ignore residuals see the usual zero gap.
    points[:3] = np.where(hidden[..., None], 0.0, traj.positions).transpose(2, 1, 0)
    c3d = ezc3d.c3d()
    point = c3d["parameters"]["POINT"]
    point["RATE"]["value"] = np.array([float(traj.rate)])
    point["LABELS"]["value"] = list(traj.names)
    point["UNITS"]["value"] = ["mm"]
    c3d["data"]["points"] = points
    c3d["data"]["meta_points"]["residuals"] = np.where(hidden, -1.0, 0.0).T[None]
    c3d.write(str(path))


def _load(path: Path) -> ezc3d.c3d:
    try:
        return ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d maps its C++ errors onto several Python types
        raise InputError(f"{path}: not a readable C3D file ({_first_line(exc)})") from exc


def _labels(c3d: ezc3d.c3d, n_markers: int, path: Path) -> list[str]:
    """POINT:LABELS, continued in LABELS2, LABELS3, ... past 255 markers."""
    point = c3d["parameters"]["POINT"]
    keys = [k for k in point if re.fullmatch(r"LABELS\d*", k)]
    keys.sort(key=lambda k: int(k[len("LABELS") :] or 1))
    labels = [str(label).strip() for key in keys for label in point[key]["value"]]
    if n_markers == 0 or not labels:
        raise InputError(f"{path}: C3D file has no labeled points")
    if len(labels) < n_markers:
        raise InputError(f"{path}: C3D file has {len(labels)} point labels for {n_markers} points")
    labels = labels[:n_markers]
    # A blank label names nothing: the output would hold markers no one can tell apart.
    blank = [i for i, label in enumerate(labels) if not label]
    if len(blank) == n_markers:
        raise InputError(f"{path}: C3D file has no point labels (all {n_markers} are blank)")
    if blank:
        raise InputError(f"{path}: C3D point {blank[0] + 1} of {n_markers} has a blank label")
    return labels


def _check_complete(c3d: ezc3d.c3d, path: Path) -> None:
    """Compare the file size with what its header declares.

    ezc3d stops silently at the end of a truncated file and rewrites its header to
    match, so the declared frame count is read from the raw header here.
    """
    with path.open("rb") as f:
        header = f.read(_BLOCK)
        f.seek((header[0] - 1) * _BLOCK + 3)
        order = ">" if f.read(1) == bytes([_MIPS]) else "<"
    n_points, n_analog, first, last = struct.unpack_from(order + "4H", header, 2)
    (data_start,) = struct.unpack_from(order + "H", header, 16)
    word = 4 if c3d["parameters"]["POINT"]["SCALE"]["value"][0] < 0 else 2  # float or int
    frames = max(last - first + 1, 0)
    expected = (data_start - 1) * _BLOCK + frames * word * (4 * n_points + n_analog)
    size = path.stat().st_size
    if size < expected:
        raise InputError(f"{path}: truncated C3D file ({size} of {expected} bytes)")


def _check_writable(path: Path) -> None:
    """ezc3d writes nothing, silently, to a path it cannot open; fail loudly instead."""
    try:
        path.open("wb").close()
    except OSError as exc:
        raise InputError(f"{path}: cannot write ({exc.strerror})") from exc


def _first_line(exc: Exception) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__
