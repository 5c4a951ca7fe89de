"""``markerflow pose``: articulated pose from per-camera OpenPose keypoints or images, written as TRC and a PNG overlay."""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from formulations.cameras.rig import Rig
from formulations.errors import FormulationError
from formulations.pose.apf import AnnealingSchedule
from formulations.pose.body import BodyModel
from formulations.pose.from_subject import subject_body
from formulations.pose.human import human_model
from formulations.pose.keypoints import BODY_25B, KeypointPairs
from formulations.pose.kinematics import forward_kinematics
from formulations.subject.model import SubjectModel
from service.cli import report
from service.cli.output import check_writable_output
from service.errors import InputError
from service.io.calibration import METRES_PER_UNIT, load_calibration
from service.io.formats import write_labeled
from service.io.recording import LabeledTrajectories, SourceFile
from service.pose.images import fit_images, image_folders, read_frame
from service.pose.openpose import camera_folders, match_cameras, missing_frames_warning, read_keypoint_frames
from service.pose.overlay import write_overlay
from service.pose.participant import choose_participant
from service.pose.run import PoseFit, fit_keypoints
from service.words import counted

EMPTY_ROWS = 10  # frame_rows: empty TRC rows allowed per fitted frame before the numbering is refused


def run_pose(input: Path, calibration: Path, output: Path, model_path: Path | None, particles: int, layers: int,
             rate: float, seed: int, refine: bool = True) -> None:
    """Fit the body to INPUT's keypoints frame by frame; write the joints as TRC and the overlay PNG beside it.
    ``refine``: polish each keypoint fit after the APF (``service.pose.run.fit_keypoints``)."""
    if output.suffix.lower() != ".trc":
        raise InputError(f"{output}: the pose is written as .trc")
    check_writable_output(output, input)
    if not (math.isfinite(rate) and rate > 0):
        raise InputError(f"--rate must be a finite number > 0 (frames per second), got {rate}")
    if seed < 0:
        raise InputError(f"--seed must be >= 0, got {seed}")
    try:
        schedule = AnnealingSchedule(particles, layers)
    except FormulationError as error:
        raise InputError(f"--particles/--layers: {error}") from None
    unit = _calibration_unit(calibration)
    metres = METRES_PER_UNIT[unit]
    model = _subject_body(model_path, metres) if model_path else None
    picture = output.with_suffix(".png")
    if camera_folders(input):
        frames = read_keypoint_frames(input)
        cameras = match_cameras(frames.cameras, load_calibration(calibration), calibration)
        numbers = frames.numbers
        rows = frame_rows(numbers, input)
        report.warn(missing_frames_warning(frames))
        report.warn(empty_rows_warning(numbers, rows))
        detections = choose_participant(Rig.of(cameras), frames.people)
        with frame_progress(f"fitting {input.name}") as progress:
            fit = fit_keypoints(cameras, detections, metres, model, schedule, seed, progress, refine)
        if model is not None:
            report.warn(unused_keypoints_warning(model, detections))
        best = int(np.argmax((detections[..., 2] > 0).sum(axis=(0, 2))))
        write_overlay(picture, cameras[best], fit.model, fit.positions, input.name, detections=detections[:, best],
                      numbers=numbers)
    else:
        numbers, folders = image_folders(input)
        if not folders:
            raise InputError(f"{input}: neither per-camera OpenPose folders (camNN_json) nor per-camera image folders")
        cameras = match_cameras(list(folders), load_calibration(calibration), calibration)
        files = list(folders.values())
        rows = frame_rows(numbers, input)
        report.warn(empty_rows_warning(numbers, rows))
        with frame_progress(f"fitting {input.name}") as progress:
            fit = fit_images(cameras, files, model or human_model().scaled(1.0 / metres), metres, schedule, seed, progress)
        write_overlay(picture, cameras[0], fit.model, fit.positions, input.name,
                      image=lambda f: read_frame(files[0][f], cameras[0]))
    write_labeled(output, _trajectories(fit, metres, rate, numbers, rows), _numbering(unit, rows, rate))
    _print(fit, output, picture)


def unused_keypoints_warning(model: BodyModel, detections: np.ndarray) -> str | None:
    """A line when a subject model names fewer than half of the keypoints the cameras detected:
    the fit follows those alone (a model naming only Neck was fitted with a 4.6 px error while
    its ankle came out 0.5 m off Pose2Sim's), and the others are not written."""
    detected = [name for k, name in enumerate(BODY_25B) if (detections[..., k, 2] > 0).any()]
    used = {BODY_25B[k] for k in KeypointPairs.of(model).keypoints}
    if 2 * len(used & set(detected)) >= len(detected):
        return None
    unused = [name for name in detected if name not in used]
    return (f"warning: the model names {len(used & set(detected))} of the {len(detected)} keypoints detected "
            f"({', '.join(sorted(used))}); the fit follows those alone and ignores {', '.join(unused[:8])}"
            f"{' ...' if len(unused) > 8 else ''} (name the model's joints as BODY_25B keypoints)")


def _calibration_unit(calibration: Path) -> str:
    """Pose2Sim and caliscope TOML are in metres; markerflow JSON names its unit."""
    if calibration.suffix.lower() != ".json":
        return "m"
    try:
        unit = json.loads(calibration.read_text()).get("units")
    except (OSError, ValueError, AttributeError):
        unit = None  # load_calibration names the problem
    return unit if unit in METRES_PER_UNIT else "mm"


def _subject_body(path: Path, metres_per_unit: float) -> BodyModel:
    """The body of a subject model; a line names the joints it leaves out (on segments not
    joined to the largest tree: the model's RAnkle went missing from the TRC without a word)."""
    try:
        subject = SubjectModel.from_json(path.read_text())
        body = subject_body(subject, metres_per_unit)
        left = [joint.name for joint in subject.joints if joint.name not in {node.name for node in body.nodes}]
        if left:
            report.warn(f"warning: {path.name}: {len(left)} joint{'s' * (len(left) > 1)} on segments not joined to "
                        f"the rest of the body, not fitted or written: {', '.join(left[:8])}")
        return body
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    except FormulationError as error:
        raise InputError(f"{path}: {error}") from None


def _trajectories(fit: PoseFit, metres_per_unit: float, rate: float, numbers: list[int],
                  rows: np.ndarray) -> LabeledTrajectories:
    """The joints that are points of their own (not a second set of DOF at an earlier joint's place, as the
    spine at the pelvis or a clavicle at the neck), in mm, one row per ``rows`` number: the fitted frames
    ``numbers`` in theirs, empty cells in the others. The rows step ``rate / step`` per second."""
    rest = forward_kinematics(fit.model, np.zeros((1, fit.model.dof))).positions[0]
    kept = [i for i in range(len(rest)) if not any(np.allclose(rest[i], rest[j]) for j in range(i))]
    positions = np.full((len(rows), len(kept), 3), np.nan)
    fitted = np.searchsorted(rows, numbers)
    positions[fitted] = fit.positions[:, kept] * metres_per_unit * 1000.0
    occluded = np.isnan(positions).any(axis=2)
    step = int(rows[1] - rows[0]) if len(rows) > 1 else 1
    return LabeledTrajectories([fit.names[i] for i in kept], positions, occluded, rate / step)


def frame_rows(numbers: list[int], input: Path) -> np.ndarray:
    """The TRC's rows: every frame number from the input's first to its last, in the step all its numbers
    share (a take OpenPose ran on every other frame keeps its step). A row per number, not per file: a
    TRC's rows are evenly spaced in time (markerflow's reader refuses a jump, ``check_rows``), so a frame
    no camera has a file for is a row of empty cells, as in any take.

    Raises:
        InputError: mostly empty rows (more than ``EMPTY_ROWS`` per fitted frame): a file of another
            take or numbered otherwise, which would have filled the table with empty rows.
    """
    step = int(np.gcd.reduce(np.diff(numbers))) if len(numbers) > 1 else 1
    count = (numbers[-1] - numbers[0]) // step + 1
    if count - len(numbers) > EMPTY_ROWS * len(numbers):
        jump = int(np.argmax(np.diff(numbers)))
        raise InputError(f"{input}: no camera has a file between frames {numbers[jump]} and {numbers[jump + 1]}, "
                         f"so the TRC would be {count - len(numbers)} empty rows for {len(numbers)} frames: is a "
                         "file from another take or numbered otherwise? Move it out, or fit the parts apart")
    return np.arange(numbers[0], numbers[-1] + 1, step)


def empty_rows_warning(numbers: list[int], rows: np.ndarray) -> str | None:
    """A line naming the frames no camera has a file for, written as rows of empty cells."""
    empty = np.setdiff1d(rows, numbers)
    if not len(empty):
        return None
    listed = ", ".join(map(str, empty[:8].tolist())) + (" ..." if len(empty) > 8 else "")
    return (f"warning: no camera has a file for {counted(len(empty), 'frame')} between {numbers[0]} and "
            f"{numbers[-1]} ({listed}): written as rows of empty cells")


def _numbering(unit: str, rows: np.ndarray, rate: float) -> SourceFile:
    """The TRC's ``Frame#`` and ``Time`` of the input's frame numbers: ``Frame#`` is the number + 1, as a TRC
    counts from 1 (Pose2Sim's TRC of ``cam01.0000.json`` … numbers its rows from 1 too), and ``Time`` the
    number / rate, so a take whose files start at 5 starts at 5 / rate."""
    frame = rows.astype(float)
    return SourceFile.of_table(unit, frame + 1, frame / rate)


def _print(fit: PoseFit, output: Path, picture: Path) -> None:
    unobserved = int((~fit.observed).sum())
    checked = int(np.isfinite(fit.reprojection).sum())
    error = (f"median reprojection error {np.nanmedian(fit.reprojection):.1f} px over {checked} detections" if checked
             else "fitted to edges + foreground")
    report.out.print(f"{len(fit.positions)} frames, {unobserved} without data (predicted); {error}; "
                     f"{fit.seconds_per_frame:.2f} s/frame -> {output}, {picture}", highlight=False)


@contextmanager
def frame_progress(description: str) -> Iterator[Callable[[int, int], None] | None]:
    """Progress over frames on stderr, as ``report.window_progress`` does over windows."""
    if report.quiet:
        yield None
    elif report.err.is_terminal:
        columns = (TextColumn(description), BarColumn(), MofNCompleteColumn(), TextColumn("frames"), TimeRemainingColumn())
        with Progress(*columns, console=report.err, transient=True) as progress:
            task = progress.add_task(description, total=None)
            yield lambda done, total: progress.update(task, completed=done, total=total)
    else:
        began, step = time.monotonic(), [0]

        def advance(done: int, total: int) -> None:
            if done == total or done - step[0] >= max(1, total // report.PLAIN_LINES):
                print(f"{description}: {done}/{total} frames, {time.monotonic() - began:.0f} s", file=sys.stderr, flush=True)
                step[0] = done

        yield advance
