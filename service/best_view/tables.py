"""The best-view command's tables: view costs in, chosen cameras out.

COSTS.csv has the header ``frame,object,camera,cost`` and one row per triple: ``frame``
an integer, ``object`` and ``camera`` any text, ``cost`` a finite number (|cost| <= 1e100), lower is
better. Every object needs a row for every camera (all cameras named in the file) in
every frame it appears in; its frames are taken in increasing order as consecutive.
CHOICES.csv has the header ``frame,object,camera``: one row per frame and object, in
frame order, objects in the order they first appear in COSTS.csv.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from formulations.best_view.selection import MAX_COST
from service.errors import InputError
from service.io.formats.replace_file import replacing

COSTS_HEADER = ["frame", "object", "camera", "cost"]
CHOICES_HEADER = ["frame", "object", "camera"]


@dataclass(frozen=True)
class ObjectCosts:
    """One object's ``(F, M)`` costs over its frames (sorted) and the file's cameras."""

    name: str
    frames: np.ndarray
    costs: np.ndarray


def read_view_costs(path: Path) -> tuple[list[str], list[ObjectCosts]]:
    """The cameras and each object's cost matrix of a COSTS.csv.

    Raises:
        InputError: unreadable file, wrong header, a row without four cells, a frame
            that is not an integer, a cost that is not a finite number, a triple given
            twice, a missing triple, or no rows.
    """
    rows = _rows(path)
    if not rows or [cell.strip() for cell in rows[0][1]] != COSTS_HEADER:
        raise InputError(f"{path}: header should be {','.join(COSTS_HEADER)}")
    table: dict[tuple[str, int, str], float] = {}
    for line, row in rows[1:]:
        if len(row) != 4:
            raise InputError(f"{path}:{line}: {len(row)} cells, expected 4 ({','.join(COSTS_HEADER)})")
        frame, name, camera, cost = (cell.strip() for cell in row)
        key = (name, _integer(frame, path, line), camera)
        if key in table:
            raise InputError(f"{path}:{line}: frame {key[1]}, object {name!r}, camera {camera!r} is given twice")
        table[key] = _cost(cost, path, line)
    if not table:
        raise InputError(f"{path}: no cost rows")
    cameras = list(dict.fromkeys(camera for _, _, camera in table))
    frames_of: dict[str, set[int]] = {}
    for owner, number, _ in table:
        frames_of.setdefault(owner, set()).add(number)
    objects = []
    for name, frame_set in frames_of.items():
        frames = np.array(sorted(frame_set))
        costs = np.empty((len(frames), len(cameras)))
        for i, frame in enumerate(frames):
            for b, camera in enumerate(cameras):
                if (name, int(frame), camera) not in table:
                    raise InputError(f"{path}: no cost for frame {frame}, object {name!r}, camera {camera!r}")
                costs[i, b] = table[(name, int(frame), camera)]
        objects.append(ObjectCosts(name, frames, costs))
    return cameras, objects


def write_choices(path: Path, cameras: list[str], objects: list[ObjectCosts], chosen: list[np.ndarray]) -> None:
    """CHOICES.csv: ``frame,object,camera`` for every frame and object, in frame order.

    Raises:
        InputError: the file cannot be written.
    """
    rows = [(int(frame), i, cameras[camera]) for i, (obj, views) in enumerate(zip(objects, chosen))
            for frame, camera in zip(obj.frames, views)]
    rows.sort(key=lambda row: (row[0], row[1]))
    with replacing(path) as temp, temp.open("w", newline="", encoding="utf-8") as f:  # whole or not at all
        writer = csv.writer(f)
        writer.writerow(CHOICES_HEADER)
        writer.writerows((frame, objects[i].name, camera) for frame, i, camera in rows)


def _rows(path: Path) -> list[tuple[int, list[str]]]:
    """The non-blank rows, each with the file's line it starts on (a blank line, and a line
    break inside a quoted cell, counted as an editor counts them; LF, CRLF or CR endings):
    numbering the rows left after the blank ones were dropped named a line too early after
    every blank line."""
    try:
        # utf-8-sig: spreadsheets often save with a byte-order mark.
        with path.open(newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f)
            rows, before = [], 0  # before: the lines read up to the row's start
            for row in reader:
                if row:
                    rows.append((before + 1, row))
                before = reader.line_num  # past a quoted cell's line breaks too
            return rows
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    except (csv.Error, UnicodeDecodeError) as error:
        raise InputError(f"{path}: not a CSV table ({error})") from None


def _integer(cell: str, path: Path, line: int) -> int:
    try:
        return int(cell)
    except ValueError:
        raise InputError(f"{path}:{line}: frame {cell!r} is not an integer") from None


def _cost(cell: str, path: Path, line: int) -> float:
    try:
        value = float(cell)
    except ValueError:
        raise InputError(f"{path}:{line}: cost {cell!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"{path}:{line}: cost {cell!r} is not finite")
    if abs(value) > MAX_COST:  # window sums would overflow
        raise InputError(f"{path}:{line}: cost {cell!r} is out of range (|cost| <= {MAX_COST:g})")
    return value
