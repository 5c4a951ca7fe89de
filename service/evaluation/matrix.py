"""The accuracy matrix (issue 11): real recordings x conditions x seeds x formulations.

Each cell simulates one condition on one recording (``simulate_cloud``), labels it and
scores it (``evaluate``), with the accuracy of every 1,000-frame block. The recordings are
split once, here, into a tuning half (tune on it only) and a validation half (report it).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from service.evaluation.cloud import evaluate
from service.evaluation.label_jumps import label_jumps
from service.evaluation.scenario import Scenario
from service.evaluation.scores import block_counts, counts_within
from service.io.formats import read_labeled
from service.io.recording import Recording

DATA = Path(__file__).resolve().parents[3] / "shared" / "data"
HALVES = ("tuning", "validation")
BASELINE = "nn-hungarian"  # the formulation every other one must beat


@dataclass(frozen=True)
class MatrixRecording:
    """One labeled take of the shared data.

    Attributes:
        name: Short id used in tables and on the command line.
        path: File under the data folder.
        lab: Who recorded it (halves mix labs).
        half: ``"tuning"`` or ``"validation"``.
        start: Fixed first frame; None: the first frame with the most markers present.
        exclude: Columns that are not markers of their own, left out.
    """

    name: str
    path: str
    lab: str
    half: str
    start: int | None = None
    exclude: tuple[str, ...] = ()


_CMU, _KTK, _OSIM = "c3d_mocaprecovery_cmu_hdm05_numediart", "c3d_kineticstoolkit", "mocap_opensim"
_EZC = "c3d_ezc3d_testfiles"

# Pairs from one lab or subject go to opposite halves (85/135, racing/basket, walking2/5,
# gait2354 walk/static, Rajagopal run/static); both halves hold a take over 3,000 frames and
# takes with real gaps. The pose2sim TRCs are left out: triangulated video keypoints, not markers.
RECORDINGS: tuple[MatrixRecording, ...] = (
    MatrixRecording("cmu-85_02", f"{_CMU}/85_02.c3d", "CMU", "tuning"),
    # The unlabelled *0, *1, *2 are exact copies of LFHD, CLAV and LFWT in every frame.
    MatrixRecording("hdm05-mm", f"{_CMU}/HDM_mm_01-02_03_120.c3d", "HDM05 (MPI)", "tuning", None, ("*0", "*1", "*2")),
    MatrixRecording("ezc3d-qualisys", f"{_EZC}/Qualisys.c3d", "Qualisys test file", "tuning"),
    MatrixRecording("ezc3d-bts", f"{_EZC}/BTS.c3d", "BTS test file", "tuning"),
    MatrixRecording("ktk-racing", f"{_KTK}/kinematics_racing_full.c3d", "UQAM (Kinetics Toolkit)", "tuning"),
    MatrixRecording("osim-walking2", f"{_OSIM}/opensim-core_walking2.c3d", "OpenSim core", "tuning"),
    MatrixRecording("gait2354-walk1", f"{_OSIM}/gait2354_subject01_walk1.trc", "OpenSim gait2354", "tuning"),
    MatrixRecording("rajagopal-static", f"{_OSIM}/rajagopal_static_run.trc", "Rajagopal 2016", "tuning"),
    MatrixRecording("cmu-135_02", f"{_CMU}/135_02.c3d", "CMU", "validation"),
    MatrixRecording("numediart-rolling", f"{_CMU}/03_rolling.c3d", "numediart (Qualisys)", "validation"),
    MatrixRecording("ezc3d-vicon", f"{_EZC}/Vicon.c3d", "Vicon test file", "validation"),
    # Frame 361, not 1632 (the first with all but Sync), keeps 3,317 frames for the blocks.
    MatrixRecording("ktk-basket", f"{_KTK}/kinematics_basket_sprint.c3d", "UQAM (Kinetics Toolkit)", "validation", 361),
    MatrixRecording("ktk-tennis", f"{_KTK}/kinematics_tennis_serve.c3d", "UCL Aspire CREATe", "validation"),
    MatrixRecording("osim-walking5", f"{_OSIM}/opensim-core_walking5.c3d", "OpenSim core", "validation"),
    MatrixRecording("gait2354-static", f"{_OSIM}/gait2354_subject01_static.trc", "OpenSim gait2354", "validation"),
    MatrixRecording("hamner-running", f"{_OSIM}/hamner_subject02_running.trc", "Hamner (OpenSim)", "validation"),
    MatrixRecording("rajagopal-run", f"{_OSIM}/rajagopal_motion_capture_run.trc", "Rajagopal 2016", "validation"),
)

# The default (1.5 mm, 15 % deleted in 12-frame bursts, 3 ghosts/frame) and one
# harder setting at a time, then all of them; ghosts spread 200 mm, windows of 20 frames.
_DEFAULT = Scenario(noise_mm=1.5, drop_rate=0.15, drop_burst_frames=12, ghosts_per_frame=3.0)
_DROP_30 = replace(_DEFAULT, drop_rate=0.3, drop_burst_frames=60.0)
CONDITIONS: dict[str, Scenario] = {
    "clean": replace(_DEFAULT, noise_mm=0.5, drop_rate=0.0, ghosts_per_frame=0.0),
    "default": _DEFAULT,
    "noise-2": replace(_DEFAULT, noise_mm=2.0),
    "noise-3": replace(_DEFAULT, noise_mm=3.0),
    "noise-4": replace(_DEFAULT, noise_mm=4.0),
    "drop-30": _DROP_30,
    "ghosts-10": replace(_DEFAULT, ghosts_per_frame=10.0),
    "combined": replace(_DROP_30, noise_mm=4.0, ghosts_per_frame=10.0),
    # Three markers' points in the cloud with no name, as `track --start` leaves those
    # absent in its start frame: persistent tracks no marker should take.
    "unnamed-3": replace(_DEFAULT, unnamed_markers=3),
}


@dataclass(frozen=True)
class Take:
    """A recording ready to simulate: markers absent at ``start`` dropped.

    Attributes:
        truth: The trajectories of the kept markers, millimetres, all frames.
        start: First frame used; every kept marker is present there.
        dropped: Names of the markers absent at ``start``.
        own_gaps: Fraction of kept marker-samples missing in the file from ``start`` on;
            these add to the simulated deletions.
    """

    recording: MatrixRecording
    truth: Recording
    start: int
    dropped: tuple[str, ...]
    own_gaps: float

    @property
    def frames(self) -> int:
        return self.truth.n_frames - self.start


def prepare(recording: MatrixRecording, data: Path = DATA, frame_step: int = 1) -> Take:
    """Read a take: excluded columns left out, start chosen, markers absent there dropped.

    The start is ``recording.start`` if fixed, else ``argmax_f #{n : n present in f}``,
    the first frame with the most markers present in the file. ``frame_step`` > 1 keeps every
    ``frame_step``-th frame from the start on (and before it, in step): the take as a system
    capturing at 1 / ``frame_step`` of its rate would have recorded it.
    """
    read = read_labeled(data / recording.path)
    own = [i for i, n in enumerate(read.names) if n not in recording.exclude]
    full = Recording([read.names[i] for i in own], read.positions[:, own], read.rate)
    missing = full.missing()
    start = int(np.argmax((~missing).sum(axis=1))) if recording.start is None else recording.start
    keep = ~missing[start]
    truth = Recording([n for n, k in zip(full.names, keep) if k], full.positions[:, keep], full.rate)
    truth = truth.every(frame_step, start % frame_step)
    dropped = tuple(n for n, k in zip(full.names, keep) if not k)
    start //= frame_step
    return Take(recording, truth, start, dropped, float(truth.missing()[start:].mean()))


@lru_cache(maxsize=4)
def _take(name: str, data: Path, frame_step: int = 1) -> Take:
    return prepare(recording_named(name), data, frame_step)


def recording_named(name: str) -> MatrixRecording:
    """The matrix recording called ``name``; KeyError names the known ones."""
    for recording in RECORDINGS:
        if recording.name == name:
            return recording
    raise KeyError(f"unknown recording '{name}'; known: {', '.join(r.name for r in RECORDINGS)}")


@dataclass(frozen=True)
class CellKey:
    """Which cell: recording, condition, seed, formulation."""

    recording: str
    condition: str
    seed: int
    formulation: str


@dataclass(frozen=True)
class Cell:
    """One scored run; counts as in ``LabelScores`` (frame 0 unscored).

    Attributes:
        missed: Visible marker-frames declared occluded.
        took_ghost: Marker-frames labeled with a ghost.
        seconds_per_frame: Labeling time (simulation and scoring excluded) per frame.
        blocks: ``(marker_frames, correct)`` per block of frames (``block_counts``).
        file_jumps: Of ``marker_frames``, those where the file's own label jumped to another
            marker (``label_jumps``): its truth is not known there.
        correct_on_jumps: Of ``correct``, those among ``file_jumps``.
    """

    key: CellKey
    half: str
    frames: int
    markers: int
    accuracy: float
    swaps: int
    missed: int
    took_ghost: int
    marker_frames: int
    correct: int
    seconds_per_frame: float
    blocks: tuple[tuple[int, int], ...]
    file_jumps: int = 0
    correct_on_jumps: int = 0


def run_cell(
    key: CellKey, frames_cap: int = 0, data: Path = DATA, block_frames: int = 1000, mht_reading: bool = False,
    frame_step: int = 1,
) -> Cell:
    """Simulate, label and score one cell; ``frames_cap`` > 0 caps the frames used; ``mht_reading``
    as ``LabelingOptions.mht_reading``; ``frame_step`` as ``prepare``'s."""
    take = _take(key.recording, data, frame_step)
    frames = min(frames_cap, take.frames) if frames_cap else take.frames
    scenario = replace(CONDITIONS[key.condition], seed=key.seed, start_frame=take.start, frames=frames,
                       mht_reading=mht_reading)
    run = evaluate(take.truth, scenario, key.formulation)
    s = run.scores
    jumps = counts_within(run.capture, run.result, label_jumps(take.truth)[take.start : take.start + frames])
    return Cell(
        key, take.recording.half, frames, take.truth.n_markers, s.label_accuracy, s.swaps, s.missed,
        s.took_ghost, s.marker_frames, s.correct, run.seconds / frames,
        tuple(block_counts(run.capture, run.result, block_frames)), *jumps,
    )

