"""C3D files: read labeled marker trajectories, write markerflow's labels.

A C3D written from a C3D input is that file with only its points, their labels and
residuals replaced: analog channels, force platforms, events, subjects, trial and every
other parameter group, the frame numbering, the point rate and the length unit are copied.
"""

from __future__ import annotations

import re
from pathlib import Path

import ezc3d
import numpy as np

from service.errors import InputError
from service.io.formats.c3d_analog import ChannelParameters, fix_channels, joined_values, with_confidence
from service.io.formats.c3d_copy import detached, writable
from service.io.formats.c3d_layout import PREFIX_BYTES, c3d_layout, match_header_scale
from service.io.formats.c3d_parameters import append_entries, check_frame_numbers, float_scale
from service.io.formats.c3d_quality import SAME_SAMPLE, SampleQuality
from service.io.formats.conventions import (
    from_millimetres,
    hidden_samples,
    require_file,
    require_samples,
    to_millimetres,
    without_samples,
    zero_gaps_to_nan,
)
from service.io.formats.replace_file import replacing
from service.io.recording import UNLABELED_PREFIX, LabeledTrajectories, Recording, SourceFile, is_unlabeled


def read_c3d(path: str | Path, max_points: int | None = None, max_frames: int | None = None) -> Recording:
    """Read the labeled 3D points of a C3D file, in millimetres.

    Missing samples (negative residual, or exactly (0, 0, 0)) become NaN. The header and
    parameter section are checked (``c3d_layout``), and the point and frame counts against
    ``max_points``/``max_frames`` if given, before the C3D reader sees the file.

    Raises:
        InputError: missing, unreadable or truncated file; a broken parameter section; more
            points or frames than allowed; no labeled points, a blank label or one that is
            not UTF-8 text; zero frames; no frame rate; a length unit other than mm, cm or m;
            a label twice or an infinite or absurd coordinate (``require_samples``).
    """
    path = require_file(path)
    _check_layout(path, max_points, max_frames)
    c3d = _load(path)
    points = c3d["data"]["points"][:3]  # (3, markers, frames)
    names = _labels(c3d, points.shape[1], path)
    if points.shape[2] == 0:
        raise InputError(f"{path}: C3D file has zero frames")
    rate = float(c3d["header"]["points"]["frame_rate"])
    if not rate > 0:
        raise InputError(f"{path}: C3D point frame rate is {rate:g}; it must be a positive number of frames per second")
    units = list(c3d["parameters"]["POINT"].get("UNITS", {}).get("value", [])) or [""]
    positions = to_millimetres(points.transpose(2, 1, 0), units[0], path)
    require_samples(names, positions, path)
    source = SourceFile(units[0].strip().lower(), int(c3d["header"]["points"]["first_frame"]), detached(c3d))
    return Recording(names, zero_gaps_to_nan(positions), rate, source)


def write_c3d(path: str | Path, traj: LabeledTrajectories, source: SourceFile | None = None, start: int = 0) -> None:
    """Write ``traj`` as C3D points; occluded samples are (0, 0, 0) with residual -1.

    With a C3D ``source`` the output is a copy of it whose points named in ``traj`` hold
    the labels from input frame ``start`` on, and are missing in the input's frames before
    and after; points ``traj`` does not name keep the input's samples. Otherwise a new
    C3D of the labels alone, numbered from ``source.first_frame + start``. Either way in
    ``source.unit`` (mm without a source).

    Raises:
        InputError: nothing to write, labels that do not fit the source (a name it lacks,
            frames past its end), or the path cannot be written.
    """
    path = Path(path)
    if traj.n_frames == 0 or not traj.names:
        raise InputError(f"{path}: nothing to write (zero frames or zero markers)")
    source = source or SourceFile()
    at = 0 if source.c3d is None else start
    # a copy: ezc3d's write extends the LABELS list it is given
    try:
        c3d = _new_c3d(traj, source, start) if source.c3d is None else writable(source.c3d)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
    # the input's samples: read from the input itself, which ``writable`` leaves as read (a
    # copy beside the output's would be 1.5 kB a frame at 41 points); a new file's copied
    # before labels replace its points
    given = c3d if source.c3d is None else source.c3d
    quality = SampleQuality.of(given["data"]["points"], given["data"]["meta_points"], copied=source.c3d is None)
    outside = _with_labels(c3d, traj, quality, source.unit, at, path)
    # gathered (``unlabeled`` has the frames, with or without channels): the input's own *N
    # points were in the capture, so they were labeled or are in the new *N
    if source.c3d is not None and traj.unlabeled.shape[0]:
        _clear_unlabeled(c3d, slice(at, at + traj.n_frames), path)
    placed = _placed(traj.unlabeled, source.unit, at, c3d["data"]["points"].shape[2])
    unlabeled = np.concatenate([outside, _not_kept(placed, c3d, traj.names)], axis=1)
    if unlabeled.shape[1]:
        _with_unlabeled(c3d, unlabeled, quality, path)
    channels = with_confidence(c3d, traj, at) if traj.confidence.size else {}
    _write(c3d, path, channels)


def _new_c3d(traj: LabeledTrajectories, source: SourceFile, start: int) -> ezc3d.c3d:
    """An empty C3D with one point per marker, ``traj``'s frames numbered from the input's."""
    c3d = ezc3d.c3d()
    point = c3d["parameters"]["POINT"]
    point["RATE"]["value"] = np.array([float(traj.rate)])
    point["LABELS"]["value"] = list(traj.names)
    point["UNITS"]["value"] = [source.unit]
    # a C3D counts frames from 1: a table counted from 0 starts at its first (first_frame -1)
    c3d["header"]["points"]["first_frame"] = check_frame_numbers(max(source.first_frame + start, 0), traj.n_frames)
    c3d["data"]["points"] = np.ones((4, len(traj.names), traj.n_frames))
    c3d["data"]["meta_points"]["residuals"] = np.zeros((1, len(traj.names), traj.n_frames))
    return c3d


def _with_labels(c3d: ezc3d.c3d, traj: LabeledTrajectories, quality: SampleQuality, unit: str, start: int,
                 path: Path) -> np.ndarray:
    """Replace the points ``traj`` names (in place): the labels in frames ``start ..``, missing
    in every other frame, each with the residual and camera mask of the input sample it took
    (``c3d_quality``). Returns ``(3, U, frames)`` the input samples of those points outside the
    labeled frames, one channel per point that has any (NaN elsewhere): they are kept, unlabeled."""
    points, meta = c3d["data"]["points"], c3d["data"]["meta_points"]
    columns = _columns(_labels(c3d, points.shape[1], path), traj.names, path)
    frames = slice(start, start + traj.n_frames)
    if start < 0 or frames.stop > points.shape[2]:
        raise InputError(f"{path}: labels of frames {start}..{frames.stop - 1} do not fit the input's "
                         f"{points.shape[2]} frames")
    own = points[:3, columns]
    outside = (meta["residuals"][0, columns] >= 0) & np.isfinite(own).all(axis=0) & (own != 0).any(axis=0)
    outside[:, frames] = False
    kept = np.where(outside, own, np.nan)[:, outside.any(axis=1)]
    hidden = hidden_samples(traj)
    values = np.where(hidden[..., None], np.nan, from_millimetres(traj.positions, unit)).T  # (3, M, F')
    residuals, masks = quality.taken(values, start)
    points[:3, columns], meta["residuals"][0, columns] = 0.0, -1.0
    # (0, 0, 0) under residual -1: readers that ignore residuals see the usual zero gap.
    points[:3, columns, frames] = np.nan_to_num(values, nan=0.0)
    meta["residuals"][0, columns, frames] = np.where(hidden.T, -1.0, residuals)
    if masks is not None:
        meta["camera_masks"][:, columns] = False
        meta["camera_masks"][:, columns, frames] = masks
    return kept


def _clear_unlabeled(c3d: ezc3d.c3d, frames: slice, path: Path) -> None:
    """The input's own unlabeled trajectories (``*N``) missing in ``frames`` (in place)."""
    points, meta = c3d["data"]["points"], c3d["data"]["meta_points"]
    columns = [i for i, label in enumerate(_labels(c3d, points.shape[1], path)) if is_unlabeled(label)]
    points[:3, columns, frames], meta["residuals"][0, columns, frames] = 0.0, -1.0


def _placed(unlabeled: np.ndarray, unit: str, start: int, frames: int) -> np.ndarray:
    """``(3, U, frames)``: the ``(F, U, 3)`` mm channels in ``unit`` from frame ``start``, NaN elsewhere."""
    placed = np.full((3, unlabeled.shape[1], frames), np.nan)
    placed[:, :, start : start + len(unlabeled)] = from_millimetres(unlabeled, unit).T
    return placed


def _not_kept(placed: np.ndarray, c3d: ezc3d.c3d, names: list[str]) -> np.ndarray:
    """``placed`` ``(3, U, frames)`` without the samples a kept input point holds in that frame
    (``without_samples``): a copy keeps the points ``names`` does not label (a marker a subject
    model lacks), whose samples, free in the capture, came out again as ``*N``."""
    labels = point_labels(c3d)
    kept = [i for i, label in enumerate(labels) if label not in names and not is_unlabeled(label)]
    valid = c3d["data"]["meta_points"]["residuals"][0, kept] >= 0  # (K, frames)
    samples = np.where(valid[None], c3d["data"]["points"][:3, kept], np.nan)  # (3, K, frames), the file's unit
    return without_samples(placed.T, samples.T, SAME_SAMPLE).T


def _with_unlabeled(c3d: ezc3d.c3d, unlabeled: np.ndarray, quality: SampleQuality, path: Path) -> None:
    """One point per channel of ``unlabeled`` ``(3, U, frames)`` (the file's unit, NaN where
    empty), in place: first in the file's own ``*N`` points left empty (a relabel emptied them,
    and each run on markerflow's own output added as many again), the rest appended, named
    ``*N`` from one past the highest such name the file has. Each sample is an input sample and
    keeps its residual and camera mask (``c3d_quality``), as a label does."""
    points, meta = c3d["data"]["points"], c3d["data"]["meta_points"]
    labels = _labels(c3d, points.shape[1], path)
    empty = [i for i, label in enumerate(labels) if is_unlabeled(label) and (meta["residuals"][0, i] < 0).all()]
    reused = empty[: unlabeled.shape[1]]
    present = np.isfinite(unlabeled).all(axis=0)  # (channels, frames)
    taken, masks = quality.taken(unlabeled, 0)
    values, residual = np.where(present, unlabeled, 0.0), np.where(present, taken, -1.0)
    points[:3, reused], meta["residuals"][0, reused] = values[:, : len(reused)], residual[: len(reused)]
    if masks is not None:
        meta["camera_masks"][:, reused] = masks[:, : len(reused)]
    extra = unlabeled.shape[1] - len(reused)
    if not extra:
        return
    first = 1 + max((int(label[1:]) for label in labels if is_unlabeled(label)), default=-1)
    added = np.ones((4, extra, points.shape[2]))
    added[:3] = values[:, len(reused) :]
    c3d["data"]["points"] = np.concatenate([points, added], axis=1)
    meta["residuals"] = np.concatenate([meta["residuals"], residual[None, len(reused) :]], axis=1)
    if masks is not None:
        meta["camera_masks"] = np.concatenate([meta["camera_masks"], masks[:, len(reused) :]], axis=1)
    names = [f"{UNLABELED_PREFIX}{first + k}" for k in range(extra)]
    append_entries(c3d, "LABELS", names)
    append_entries(c3d, "DESCRIPTIONS", [""] * len(names))  # ezc3d blanks every description if one is lacking


def _columns(labels: list[str], names: list[str], path: Path) -> list[int]:
    """The input point of each labeled marker: the one of the same name."""
    column = {label: i for i, label in enumerate(labels)}
    absent = [name for name in names if name not in column]
    if absent:
        raise InputError(f"{path}: the input has no point named {absent[0]!r}")
    return [column[name] for name in names]


def _check_layout(path: Path, max_points: int | None, max_frames: int | None) -> None:
    with path.open("rb") as f:
        prefix = f.read(PREFIX_BYTES)
    try:
        c3d_layout(prefix, path.stat().st_size).check_limits(max_points, max_frames)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None


def _load(path: Path) -> ezc3d.c3d:
    try:
        return ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d maps its C++ errors onto several Python types
        raise InputError(f"{path}: not a readable C3D file ({_first_line(exc)})") from exc


def _labels(c3d: ezc3d.c3d, n_markers: int, path: Path) -> list[str]:
    """POINT:LABELS, continued in LABELS2, LABELS3, ... past 255 markers, checked."""
    labels = point_labels(c3d)
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
    # ezc3d decodes bytes outside UTF-8 as lone surrogates, which no JSON or text output can hold.
    garbled = [i for i, label in enumerate(labels) if not _is_utf8(label)]
    if garbled:
        raise InputError(f"{path}: C3D point {garbled[0] + 1} of {n_markers} has a label that is not UTF-8 text "
                         f"({labels[garbled[0]].encode('utf-8', 'backslashreplace').decode()})")
    return labels


def point_labels(c3d: ezc3d.c3d) -> list[str]:
    """POINT:LABELS, continued in LABELS2, LABELS3, ... past 255 markers."""
    return [str(label).strip() for label in joined_values(c3d["parameters"]["POINT"], "LABELS")]


def _is_utf8(label: str) -> bool:
    try:
        label.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def _write(c3d: ezc3d.c3d, path: Path, channels: ChannelParameters) -> None:
    """Write to a new file beside ``path`` and rename it there: ezc3d appends ``.c3d`` to any
    other ending (``OUT.C3D`` would be left empty and ``OUT.C3D.c3d`` written), writes nothing,
    silently, where it cannot open the file, and a failure must not leave a half file in place
    of one the user had."""
    with replacing(path, ".c3d") as temp:  # ezc3d creates it, umask applies
        scale = float_scale(c3d)
        c3d.write(str(temp))
        if not temp.is_file():
            raise InputError(f"{path}: cannot write there")
        _check_whole(temp, path)  # before reading it back: a full disk left it empty (an IndexError)
        fix_channels(str(temp), channels)
        match_header_scale(str(temp), scale)
        _check_whole(temp, path)  # fix_channels wrote it again


def _check_whole(temp: Path, path: Path) -> None:
    """ezc3d says nothing of a full disk: the file it leaves is empty or short of its own header."""
    try:
        _check_layout(temp, None, None)
    except InputError:
        raise InputError(f"{path}: cannot write (the file came out short: is the disk full?); any earlier "
                         "file there is untouched") from None


def _first_line(exc: Exception) -> str:
    """The reader's own first line, without its advice to set an ezc3d option: markerflow
    exposes none of them, so the user can only repair or re-export the file."""
    text = str(exc).strip()
    line = text.splitlines()[0] if text else type(exc).__name__
    return re.sub(r"\.?\s*If you want to ignore this error.*$", "", line)
