"""``markerflow model``: learn a subject (segments, joints, limb lengths) from labeled takes."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from rich.table import Table

from formulations.errors import FormulationError
from formulations.subject.far_joints import LIMB_REACH_MM, FarJoint, far_joints
from formulations.subject.fit import SubjectFit, fit_subject
from formulations.subject.grouping import Grouping
from formulations.subject.template import fit_template
from service.capture.markerset import load_template
from service.capture.model_input import MIN_SHARED
from service.capture.pooled_takes import other_subject_warning
from service.capture.span import frame_span
from service.cli.output import check_writable_output
from service.cli.report import out, warn
from service.errors import InputError
from service.io.formats import read_labeled
from service.io.formats.replace_file import replacing
from service.io.recording import LabeledTrajectories, Recording, SourceFile
from service.labeling.take_warnings import take_scale_warning


def run_model(inputs: list[Path], output: Path, centres: Path | None, markerset: str | None = None,
              start: int = 0, end: int | None = None) -> None:
    """Fit a subject model to ``inputs``, print it, write it as JSON and optionally the joint centres
    (TRC, C3D or CSV, numbered as the first take's frames ``start ..``).

    With ``markerset`` (a template name or file) the segments and joint centres come from the
    template and the takes (a static trial is enough) give the marker coordinates. Only frames
    ``start .. end - 1`` of each take are read (counted from 0, as ``track --start/--end``).
    """
    if output.suffix.lower() != ".json":  # a model is JSON: another suffix would mislead every reader
        raise InputError(f"{output}: a subject model is written as JSON; name it .json")
    check_writable_output(output, *inputs, labeled=False)
    if centres is not None:
        check_writable_output(centres, *inputs)
    if markerset is not None and centres is not None:
        raise InputError("--centres needs a fitted model: a --markerset model places its centres from markers")
    read = [read_labeled(path) for path in inputs]
    takes = [_span(take.without_unlabeled(), path, start, end) for take, path in zip(read, inputs)]  # *N: no marker
    _check_one_marker_set(takes, inputs)
    for path, take in zip(inputs[1:], takes[1:]):
        warn(other_subject_warning(takes[0], take, path.name))
    for path, take in zip(inputs, takes):  # a wrong unit reads as "too static" or "cannot group" below
        line = take_scale_warning(take)
        warn(line.replace("warning: ", f"warning: {path.name}: ", 1) if line else None)
    names, positions, rate = _pool(takes)
    try:
        if markerset is not None:
            template = load_template(markerset)
            fit = SubjectFit(fit_template(template, names, positions), Grouping([], [], []), {})
            warn(missing_segments_warning(list(template.segments), [s.name for s in fit.model.segments], template.name))
        else:
            fit = fit_subject(names, positions)
    except FormulationError as error:
        raise InputError(f"{', '.join(p.name for p in inputs)}: {error}") from None
    _print(fit, len(positions))
    warn(unseen_warning(names, positions))
    warn(far_joint_warning(far_joints(fit.model)))
    with replacing(output) as temp:  # a full disk or a Ctrl-C leaves an earlier model whole, not cut
        temp.write_text(fit.model.to_json(), encoding="utf-8")
    if centres is not None:
        _write_centres(centres, fit, rate, read[0].source, start, output)
        if len(inputs) > 1:  # one file cannot number two takes' frames as their own
            warn(f"warning: {centres.name} holds the joint centres of the {len(inputs)} takes one after another, "
                 f"numbered on from {inputs[0].name}'s frames")
    out.print(f"-> {output}" + (f", joint centres -> {centres}" if centres else ""), highlight=False)


def _write_centres(path: Path, fit: SubjectFit, rate: float, source: SourceFile | None, start: int,
                   model: Path) -> None:
    """The joint centres in the first take's unit, frame numbers and times, as ``track``
    numbers a span of it; a new file of the centres alone, not a copy of the take's C3D."""
    from service.io.formats import write_labeled

    kept = replace(source, c3d=None) if source is not None else SourceFile()
    try:
        write_labeled(path, _centre_trajectories(fit, rate), kept, start)
    except InputError as error:  # the model is written by now: say so, or the user thinks nothing was
        raise InputError(f"{error}; the model was written to {model}") from None


def _span(take: Recording, path: Path, start: int, end: int | None) -> Recording:
    """Frames ``start .. end - 1`` of ``take`` (``frame_span``'s checks, naming the file)."""
    if start == 0 and end is None:
        return take
    try:
        stop = frame_span(start, end, take.n_frames)
    except InputError as error:
        raise InputError(f"{path.name}: {error}") from None
    return Recording(take.names, take.positions[start:stop], take.rate)


def _check_one_marker_set(takes: list[Recording], paths: list[Path]) -> None:
    """Takes of one subject share their marker set: a take sharing less than half its names
    with the first is another set (or subject), and pooled with it would make one model of
    two bodies side by side.

    Raises:
        InputError: the first such take, with how many names it shares.
    """
    first = set(takes[0].names)
    for take, path in zip(takes[1:], paths[1:], strict=True):
        shared = len(first.intersection(take.names))
        if shared < MIN_SHARED * min(len(first), take.n_markers):
            folded = {name.casefold() for name in first}
            case = sum(name.casefold() in folded for name in take.names if name not in first)
            hint = f" ({case} differ from its names only in upper/lower case)" if case else ""
            raise InputError(f"{path.name}: shares {shared} of its {take.n_markers} marker names with "
                             f"{paths[0].name}{hint}; a model is fitted to takes of one marker set")


def unseen_warning(names: list[str], positions: np.ndarray) -> str | None:
    """A line naming the markers the takes never show: the model cannot place them, so a take
    labeled from it leaves them unlabeled (they are carried as the input has them)."""
    unseen = [name for name, seen in zip(names, np.isfinite(positions).all(axis=2).any(axis=0)) if not seen]
    if not unseen:
        return None
    return (f"warning: {len(unseen)} marker{'s' * (len(unseen) > 1)} never seen in the frames learned from, not in "
            f"the model: {', '.join(unseen[:12])}{' ...' if len(unseen) > 12 else ''}")


def missing_segments_warning(template: list[str], fitted: list[str], name: str) -> str | None:
    """A line naming the template's segments the take did not show (fewer than three of their
    markers, or two with no kept segment to hang from): their markers are singles, joined to
    nothing. CMU 85_02 under plug-in-gait (its pelvis markers named otherwise) lost pelvis,
    thighs, shanks and feet without a word."""
    missing = [segment for segment in template if segment not in fitted]
    if not missing:
        return None
    return (f"warning: template {name!r}: {len(missing)} of its {len(template)} segments not found in the take "
            f"({', '.join(missing[:8])}{' ...' if len(missing) > 8 else ''}): their markers are singles, joined to "
            "nothing; does the take use the template's marker names?")


def far_joint_warning(far: list[FarJoint]) -> str | None:
    """A line naming the joints no body has (``far_joints``)."""
    if not far:
        return None
    shown = ", ".join(f"{f.joint} ({f.apart_mm:.0f} mm from {f.segment})" for f in far[:3])
    return (f"warning: {len(far)} joint{'s' * (len(far) > 1)} with a centre beyond {LIMB_REACH_MM:.0f} mm of every "
            f"marker of a segment it joins, which no body joint is: {shown}; the take may not move those segments "
            "enough apart (learn from a stretch with more motion, --start/--end)")


def _pool(takes: list[Recording]) -> tuple[list[str], np.ndarray, float]:
    """The takes one after another, over the union of their marker names (NaN where a take lacks one)."""
    names = list(dict.fromkeys(name for take in takes for name in take.names))
    blocks = []
    for take in takes:
        block = np.full((take.n_frames, len(names), 3), np.nan)
        present = np.where(take.missing()[:, :, None], np.nan, take.positions)
        block[:, [names.index(n) for n in take.names]] = present
        blocks.append(block)
    return names, np.concatenate(blocks), takes[0].rate


def _centre_trajectories(fit: SubjectFit, rate: float) -> LabeledTrajectories:
    """One point per joint, named after its two segments."""
    joint_names = list(fit.centres)
    positions = np.stack([fit.centres[name] for name in joint_names], axis=1)
    occluded = np.asarray(np.isnan(positions).any(axis=2), dtype=bool)
    return LabeledTrajectories(joint_names, positions, occluded, rate)


def _print(fit: SubjectFit, frames: int) -> None:
    model = fit.model
    segments = Table(title=f"segments ({frames} frames)")
    for column in ("segment", "markers", "spread (mm)"):
        segments.add_column(column)
    for s in model.segments:
        segments.add_row(s.name, " ".join(s.markers), f"{max(s.spread):.1f}")
    for single in model.singles:
        segments.add_row("(single)", single.marker, f"{single.distances[0]:.0f} from {single.segments[0]}")
    joints = Table(title="joints")
    for column in ("joint", "segments", "fit rms (mm)"):
        joints.add_column(column)
    for j in model.joints:
        joints.add_row(j.name, " + ".join(j.segments), f"{j.rms:.1f}")
    limbs = Table(title="limb lengths")
    for column in ("segment", "between joints", "length (mm)"):
        limbs.add_column(column)
    for limb in model.limbs:
        limbs.add_row(limb.segment, " and ".join(limb.joints), f"{limb.length:.1f}")
    for table in (segments, joints, limbs):
        out.print(table)
