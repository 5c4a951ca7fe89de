"""MOTChallenge text files: detections, results, ground truth, and ``seqinfo.ini``.

One box per line, comma-separated (Milan et al. 2016):

    frame, id, bb_left, bb_top, bb_width, bb_height, conf[, x, y, z]       det.txt, results
    frame, id, bb_left, bb_top, bb_width, bb_height, consider, class, visibility    gt.txt

Frames count from 1; ``id`` is -1 in detection files. Every line of a file has the same
number of columns, from 7 to 10; any other file is refused with one line naming it. Files are
UTF-8 (ASCII numbers in practice), a byte-order mark first skipped as in capture JSON and
TOML (``service.io.utf8``): a Windows editor or spreadsheet puts one there.
"""

from __future__ import annotations

import configparser
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from service.boxes.detections import BoxDetections, BoxTracks
from service.errors import InputError
from service.io.formats.replace_file import replacing
from service.io.utf8 import utf8_file

MIN_COLUMNS, MAX_COLUMNS = 7, 10
# Frames per sequence: 55 minutes at 30 fps, a hundred times MOT17's longest. TrackEval keeps
# arrays per frame (10^5 frames: seconds), so a stray huge frame number costs for nothing.
MAX_FRAMES = 100_000
# Box coordinates and sizes, pixels: a hundred times an 8K frame. Past it a box is a broken
# line (1e300 overflowed the Kalman filter's squares), not an image.
MAX_PIXELS = 1e6


@dataclass(frozen=True)
class SequenceInfo:
    """The ``[Sequence]`` section of a ``seqinfo.ini``."""

    name: str
    length: int
    image_size: tuple[float, float] | None
    frame_rate: float | None
    image_dir: str | None
    image_ext: str
    source: Path


@dataclass(frozen=True)
class MotTable:
    """A MOTChallenge file's boxes and, per row, its line in the file (blank lines count)."""

    path: Path
    rows: np.ndarray
    lines: np.ndarray

    def at(self, row: int) -> str:
        """``"PATH: line N"`` of row ``row``, for an error that names it."""
        return f"{self.path}: line {int(self.lines[row])}"


def read_table(path: Path, empty_ok: bool = False) -> MotTable:
    """A MOTChallenge file as a ``MotTable``; one-line ``InputError`` when it is not one.

    ``empty_ok``: an empty file is ``(0, MAX_COLUMNS)`` rows (a tracker that reported no
    one), not an error."""
    text = utf8_file(path)  # a byte-order mark skipped: it was read as part of the first number ('\ufeff1')
    numbered = [(n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip()]
    if not numbered and empty_ok:
        return MotTable(path, np.empty((0, MAX_COLUMNS)), np.empty(0, int))
    if not numbered:
        raise InputError(f"{path}: no boxes in the file")
    _check_columns(path, numbered)
    table = MotTable(path, np.array([_numbers(path, n, line) for n, line in numbered]),
                     np.array([n for n, _ in numbered]))
    _check(table)
    return table


def read_rows(path: Path, empty_ok: bool = False) -> np.ndarray:
    """``(K, columns)`` floats of a MOTChallenge file (``read_table`` without line numbers)."""
    return read_table(path, empty_ok).rows


def _check_columns(path: Path, numbered: list[tuple[int, str]]) -> None:
    first = len(numbered[0][1].split(","))
    for number, line in numbered:
        width = len(line.split(","))
        if MIN_COLUMNS <= width <= MAX_COLUMNS and width == first:
            continue
        if width == 1 and len(line.split()) >= MIN_COLUMNS:
            raise InputError(f"{path}: line {number} is separated by spaces or tabs; a MOTChallenge file has "
                             "comma-separated values (frame, id, left, top, width, height, conf, ...)")
        if MIN_COLUMNS <= width <= MAX_COLUMNS:
            raise InputError(f"{path}: line {number} has {width} columns and line {numbered[0][0]} {first}; "
                             "every line of a MOTChallenge file has the same number")
        raise InputError(f"{path}: line {number} has {width} columns; a MOTChallenge file has "
                         f"{MIN_COLUMNS} to {MAX_COLUMNS} (frame, id, left, top, width, height, conf, ...) on every line")


def _numbers(path: Path, number: int, line: str) -> list[float]:
    try:
        return [float(v) for v in line.split(",")]
    except ValueError as error:
        raise InputError(f"{path}: line {number}: not a number ({error})") from None


def _check(table: MotTable) -> None:
    rows = table.rows
    bad = ~np.isfinite(rows[:, :7]).all(axis=1) | (np.abs(rows[:, 2:6]) > MAX_PIXELS).any(axis=1)
    if bad.any():
        raise InputError(f"{table.at(int(np.argmax(bad)))}: frame, id, box and confidence must be finite "
                         f"numbers, the box within {MAX_PIXELS:g} pixels")
    frames = rows[:, 0]
    bad = (frames < 1) | (frames > MAX_FRAMES) | (frames != np.round(frames))
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{table.at(row)}: frame {frames[row]:g}; frames are whole numbers from 1 to {MAX_FRAMES}")
    if (rows[:, 4:6] <= 0).any():
        raise InputError(f"{table.at(int(np.argmax((rows[:, 4:6] <= 0).any(axis=1))))}: width and height must be > 0")


def read_detections(path: Path, info: SequenceInfo | None = None) -> BoxDetections:
    """A ``det.txt`` (or a result file, whose ids are ignored) as ``BoxDetections``."""
    rows = read_rows(path)
    last = int(rows[:, 0].max())
    if info is not None and last > info.length:
        raise InputError(f"{path}: frame {last} is past the sequence's {info.length} frames ({info.source})")
    return BoxDetections(
        frame=rows[:, 0].astype(int), box=rows[:, 2:6].copy(), confidence=rows[:, 6].copy(),
        n_frames=info.length if info is not None else last, image_size=info.image_size if info is not None else None,
    )


def dense_ids(table: MotTable) -> np.ndarray:
    """The table's rows with ids renumbered 1, 2, ... in the order of the file's ids, so that
    any whole id works (TrackEval sizes arrays by the largest id). Scores do not depend on
    the numbers.

    Raises:
        InputError: An id that is not a whole number within float precision, naming its line.
    """
    ids = table.rows[:, 1]
    bad = (ids != np.round(ids)) | (np.abs(ids) > 2.0**53)  # past 2^53, floats merge distinct ids
    if bad.any():
        row = int(np.argmax(bad))
        raise InputError(f"{table.at(row)}: id {ids[row]:g} is not a whole number (of at most 2^53)")
    dense = table.rows.copy()
    dense[:, 1] = np.unique(ids, return_inverse=True)[1] + 1
    return dense


def write_tracks(path: Path, tracks: BoxTracks) -> None:
    """Write a MOTChallenge result file, sorted by frame then id; 10 significant digits keep
    an input box as it was (pixels or normalised coordinates alike)."""
    order = np.lexsort((tracks.track_id, tracks.frame))
    lines = [
        f"{f},{i},{b[0]:.10g},{b[1]:.10g},{b[2]:.10g},{b[3]:.10g},{c:.10g},-1,-1,-1"
        for f, i, b, c in zip(tracks.frame[order], tracks.track_id[order], tracks.box[order], tracks.confidence[order])
    ]
    with replacing(path) as temp:  # a Ctrl-C or a full disk leaves an earlier result whole, not cut
        temp.write_text("".join(line + "\n" for line in lines))


def read_seqinfo(path: Path) -> SequenceInfo:
    """A ``seqinfo.ini``: its length is required, image size and frame rate when present."""
    parser = configparser.ConfigParser()
    text = utf8_file(path)  # a byte-order mark skipped: configparser saw no [Sequence] after it
    try:
        parser.read_string(text, source=str(path))
        section = parser["Sequence"]
        length = int(section["seqLength"])
        size = None
        if ("imWidth" in section) != ("imHeight" in section):
            given, lacking = ("imWidth", "imHeight") if "imWidth" in section else ("imHeight", "imWidth")
            raise InputError(f"{path}: {given} without {lacking}; give both (the image size, pixels) or neither")
        if "imWidth" in section:
            size = (_positive(section, "imWidth", path), _positive(section, "imHeight", path))
        rate = _positive(section, "frameRate", path) if "frameRate" in section else None
    except (KeyError, ValueError, configparser.Error) as error:
        # configparser's messages run over several lines and quote the raw bytes: keep the first.
        detail = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise InputError(f"{path}: not a seqinfo.ini with [Sequence] seqLength ({detail})") from None
    if not 1 <= length <= MAX_FRAMES:
        raise InputError(f"{path}: seqLength {length} is invalid: a sequence has 1 to {MAX_FRAMES} frames")
    return SequenceInfo(section.get("name", path.parent.name), length, size, rate,
                        section.get("imDir"), section.get("imExt", ".jpg"), path)


def _positive(section: configparser.SectionProxy, key: str, path: Path) -> float:
    """A size or rate of ``seqinfo.ini``: a finite number > 0, or a one-line error naming it."""
    try:
        value = float(section[key])
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{path}: {key} must be a finite number > 0, got {section[key]}")
    return value
