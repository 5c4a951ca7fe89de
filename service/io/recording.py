"""Labeled and unlabeled marker data as they cross the file and wire boundaries."""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from service.errors import InputError

UNLABELED_PREFIX = "*"  # Vicon's names of unlabeled trajectories: *0, *1, ...


def is_unlabeled(name: str) -> bool:
    """A point named ``*N``: an unlabeled trajectory (a fragment no one named), not a marker."""
    return re.fullmatch(r"\*\d+", name) is not None


@dataclass(frozen=True)
class SourceFile:
    """What labeled output keeps of the file it relabels (``read_labeled`` fills it in).

    Attributes:
        unit: The input's length unit (mm, cm or m): the output is written in it.
        first_frame: The input's number of its first frame, counted from 0 (the C3D
            header's; a TRC's or markerflow CSV's first ``Frame#`` less 1, as they count from 1,
            so -1 for a table whose rows count from 0).
        first_time: The input's time of its first frame, s (a TRC's or CSV's first ``Time``;
            0 for a C3D, which has no time column).
        c3d: A C3D input as ezc3d read it: a C3D output is this file with only its points,
            their labels and residuals replaced. None for other inputs. (``Any``: ezc3d
            ships no type information.)
    """

    unit: str = "mm"
    first_frame: int = 0
    c3d: Any = None
    first_time: float = 0.0
    rows: np.ndarray | None = field(default=None, compare=False, repr=False)

    @staticmethod
    def of_table(unit: str, numbers: np.ndarray, times: np.ndarray) -> SourceFile:
        """A TRC's or CSV's numbering: its rows' frame numbers (usually counted from 1, some
        exporters from 0; a first number that is not a whole one from 0 counts as 1 for a
        C3D output) and times, which table outputs write back row by row."""
        first = float(numbers[0])
        whole = first.is_integer() and first >= 0
        return SourceFile(unit, int(first) - 1 if whole else 0, first_time=float(times[0]),
                          rows=np.column_stack([numbers, times]).astype(float))

    def numbering(self, start: int, n_frames: int, rate: float) -> list[tuple[str, str]]:
        """Frame number and time cells of input frames ``start .. start + n_frames``: a table
        input's own (frame numbers may skip, as in a decimated take), else counted on from
        the input's first frame (``first_frame + 1``, as a C3D header and a TRC count)."""
        if self.rows is not None and start + n_frames <= len(self.rows):
            return [(_number_cell(number), repr(float(time))) for number, time in self.rows[start:start + n_frames]]
        first = self.first_frame + start + 1
        return [(str(first + f), repr(self.first_time + (start + f) / rate)) for f in range(n_frames)]


def _number_cell(number: float) -> str:
    return str(int(number)) if float(number).is_integer() else repr(float(number))


@dataclass
class Recording:
    """Labeled 3D marker trajectories (ground truth, or a labeled first frame).

    Attributes:
        names: One label per marker, in column order.
        positions: ``(frames, markers, 3)`` in millimetres; NaN where a marker is missing.
        rate: Frames per second.
        source: The file it was read from, for output that keeps it; None if built in memory.
    """

    names: list[str]
    positions: np.ndarray
    rate: float
    source: SourceFile | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self.positions = np.asarray(self.positions, dtype=float)
        if self.positions.ndim != 3 or self.positions.shape[2] != 3:
            raise InputError(f"positions must be (frames, markers, 3), got {self.positions.shape}")
        if self.positions.shape[1] != len(self.names):
            raise InputError(
                f"{len(self.names)} marker names for {self.positions.shape[1]} marker columns"
            )
        if not self.rate > 0:
            raise InputError(f"frame rate must be positive, got {self.rate}")

    @property
    def n_frames(self) -> int:
        return self.positions.shape[0]

    @property
    def n_markers(self) -> int:
        return self.positions.shape[1]

    def without_unlabeled(self) -> Recording:
        """The markers alone: the unlabeled trajectories ``*N`` (``is_unlabeled``) left out."""
        keep = [i for i, name in enumerate(self.names) if not is_unlabeled(name)]
        return replace(self, names=[self.names[i] for i in keep], positions=self.positions[:, keep])

    def every(self, step: int, first: int = 0) -> Recording:
        """Frames ``first``, ``first + step``, ...: the take as a system capturing at 1/``step``
        of its rate would have recorded it (no ``source``: the file's frame numbering no longer holds)."""
        return Recording(self.names, self.positions[first::step], self.rate / step)

    def without_never_seen(self) -> tuple[Recording, list[str]]:
        """The markers with a position in some frame, and the names of those with none
        (a marker set's spare that was never placed: nothing to label or score)."""
        seen = np.asarray(~self.missing().all(axis=0), dtype=bool)
        kept = replace(self, names=[n for n, s in zip(self.names, seen.tolist()) if s], positions=self.positions[:, seen])
        return kept, [n for n, s in zip(self.names, seen.tolist()) if not s]

    def fullest_frame(self) -> tuple[int, int]:
        """The first frame with the most markers placed, and how many: where a relabel would start."""
        present = (~self.missing()).sum(axis=1)
        best = int(np.argmax(present))
        return best, int(present[best])

    def missing(self) -> np.ndarray:
        """``(frames, markers)`` bool: NaN samples, or (0, 0, 0) as some exporters write gaps."""
        p = self.positions
        return np.isnan(p).any(axis=2) | (p == 0).all(axis=2)


@dataclass
class UnlabeledCloud:
    """What a 3D capture hands markerflow: unlabeled points per frame.

    Attributes:
        points: One ``(points_in_frame, 3)`` array per frame, millimetres, in any order.
        rate: Frames per second.
        resources: Optional, per frame ``(points_in_frame, R_f)`` sparse 0/1: what each point
            consumes when points are not independent (points triangulated from camera
            detections share the detections they use). None: each point stands alone.
    """

    points: list[np.ndarray]
    rate: float
    resources: list | None = None

    @property
    def n_frames(self) -> int:
        return len(self.points)


@dataclass
class LabeledTrajectories:
    """markerflow's answer: every marker named in every frame.

    Attributes:
        names: Marker labels.
        positions: ``(frames, markers, 3)`` millimetres; NaN where the marker is occluded.
        occluded: ``(frames, markers)`` bool.
        rate: Frames per second.
        point_index: ``(frames, markers)`` index of the input point taken in that frame,
            -1 where occluded. Empty when the input had no point identities.
        filled: ``(frames, markers, 3)`` where a marker is occluded, its predicted position
            (from the rigid motion of its neighbours), NaN elsewhere. Empty when unknown.
        best_view: Camera mode: ``(frames, markers)`` index into ``view_names`` of the
            camera that shows each marker best (``service.best_view.markers``), -1 where
            the marker has no position (neither measured nor filled). Empty without cameras.
        view_names: The cameras ``best_view`` indexes; empty without cameras.
        confidence: ``(frames, markers)`` probability that each label is right (1 in the
            given first frame, NaN where no window labeled the frame). Empty when unknown.
        unlabeled: ``(frames, channels, 3)`` the input points no marker took, chained into
            unlabeled trajectories (``service.labeling.leftover_points``), NaN elsewhere;
            a C3D output writes them as points ``*N``. Empty when not gathered.
    """

    names: list[str]
    positions: np.ndarray
    occluded: np.ndarray
    rate: float
    point_index: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=int))
    filled: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    best_view: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=int))
    view_names: list[str] = field(default_factory=list)
    confidence: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    unlabeled: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))

    def best_view_names(self) -> list[list[str | None]] | None:
        """``best_view`` as camera names, None where no camera was chosen; None without cameras."""
        if not self.view_names:
            return None
        cameras = np.array([*self.view_names, None], dtype=object)  # index -1: none chosen
        names: list[list[str | None]] = cameras[self.best_view].tolist()
        return names

    @property
    def n_frames(self) -> int:
        return self.positions.shape[0]
