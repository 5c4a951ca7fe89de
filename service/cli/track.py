"""``markerflow track``: label a capture JSON, or relabel a recording from one of its frames."""

from __future__ import annotations

import json
import time
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np

from formulations.markers.noise import TakeNoise
from service.capture.capture import Capture, LabelingOptions
from service.capture.document import read_capture_document
from service.capture.formulation_spec import formulation_table
from service.capture.from_recording import capture_from_recording, capture_from_span, require_complete_first_frame
from service.capture.model_input import check_shared_names, read_model, with_model
from service.capture.span import frame_span
from service.cli.output import check_writable_output
from service.cli.pass_notes import rival_note, second_pass_note
from service.cli.report import CERTIFICATE, NO_CERTIFICATE, out, stage, warn, window_progress
from service.errors import InputError
from service.io.formats import check_labels_fit, is_copy, kept_source, read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, Recording, SourceFile
from service.labeling.absent_markers import absent_warning, in_order, with_absent
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.carried_markers import CarriedMarkers
from service.labeling.coincident import coincident_pairs
from service.labeling.exchanged import exchange_summary, handover_summary
from service.labeling.hypothesis_reading import unread_reason
from service.labeling.leftover_points import leftover_note, leftover_summary
from service.labeling.lost_subject import unnamed_span
from service.labeling.reported import lone_sightings
from service.labeling.result_warnings import early_scale_warning
from service.labeling.shape_doubt import shape_break_summary
from service.labeling.stats import WindowStats, certificate_figures, doubtful_fraction, finite_or_none, reacquisitions
from service.labeling.take_warnings import fast_markers
from service.words import counted


def run_track(
    input: Path, output: Path, formulation: str | None, window: int | None, shuffle: bool, as_json: bool = False,
    model: Path | None = None, start: int | None = None, end: int | None = None, second_pass: bool | None = None,
    keep_labels: bool = False, mht_reading: bool = False,
) -> None:
    """Label ``input`` (capture .json, or labeled .c3d/.trc/.csv) and write ``output``.

    Without ``model`` a recording is relabeled from its labels at frame ``start`` (0 when not
    given; then frame 0 must have every marker): frames ``start .. end - 1`` are labeled,
    and markers absent at ``start`` are left unlabeled, with a warning naming them.

    With ``model`` (a subject model JSON) no labeled frame is needed: a recording's labels are
    discarded, frames ``start .. end - 1`` are labeled from frame ``start`` identified by the
    model (a capture JSON's labeled first frame, if it has one, is kept; with ``keep_labels`` a
    recording's labels at ``start`` are kept too, and the model names only the markers absent
    there), and the output carries the model's marker names, in the input's unit and frame
    numbering; a .c3d of a .c3d that has every model marker is the input with those points replaced.

    ``formulation``, ``window`` and ``second_pass`` (``LabelingOptions.second_pass``)
    override a JSON document's own options when given; ``mht_reading`` turns on
    ``LabelingOptions.mht_reading``.
    A .c3d/.trc output of a .c3d/.trc input keeps the input's unit and frame numbering;
    a .c3d of a .c3d keeps everything but the points (``write_labeled``).
    Prints one line, or with ``as_json`` one JSON object (``track_summary``), on stdout,
    and a warning on stderr when many labels are doubtful.
    """
    check_writable_output(output, input)
    if keep_labels and model is None:
        raise InputError("--keep-labels keeps the --start frame's labels for a --model to complete: give --model")
    labels_at = None if model else (start, end)  # a model names the markers; a relabel starts from the labels at start
    if keep_labels and input.suffix.lower() != ".json":  # a capture JSON's labels are kept anyway
        labels_at = (start or 0, end)
    capture, options, recording, absent = _read_input(input, shuffle, labels_at)
    source = None if recording is None else recording.source
    not_kept: str | None = None  # what a .c3d output from a model loses of the input, if anything
    carried = None  # the input's markers the model lacks (``carried_markers``)
    unknown: list[str] = []  # markers labeled at start that the model lacks (--keep-labels)
    if model is not None:
        chosen = read_model(model)
        if input.suffix.lower() != ".json":
            check_shared_names(capture.names + absent, chosen, input.name)
        if labels_at is not None:  # the span is read already; the model names the markers absent at its first frame
            labeled = capture.names
            capture, absent = with_model(capture, chosen, 0, None, keep_labels=True), []
            unknown = [name for name in labeled if name not in capture.names]
        else:
            capture = with_model(capture, chosen, start or 0, end, input.suffix.lower() == ".json")
        source, not_kept = _kept(source, capture.names, output)
        if recording is not None:
            carried = CarriedMarkers.of(recording, capture.names, start or 0, capture.n_frames)
            capture = carried.out_of(capture)
    check_labels_fit(output, capture.names + absent, capture.n_frames, source, start or 0)  # before labeling, not after
    if formulation is not None:
        options = replace(options, formulation=_formulation_table(formulation))
    if window is not None:
        options = replace(options, window=window)
    if second_pass is not None:
        options = replace(options, second_pass=second_pass)
    if mht_reading:
        options = replace(options, mht_reading=True)
    labeling = CaptureLabeling(capture, options)
    if mht_reading and (reason := unread_reason(capture, options, labeling.formulation)) is not None:
        raise InputError(f"--mht-reading does not apply here: {reason}")
    unit = source.unit if source else ("the document's units" if input.suffix.lower() == ".json" else "mm")
    warn(early_scale_warning(capture, unit))
    began = time.perf_counter()
    with window_progress(f"labeling {input.name}") as progress:
        result, windows = labeling.label(progress, stage=lambda line: stage(f"labeling {input.name}: {line}"))
    written = with_absent(result, absent)
    if carried is not None and not is_copy(output, source):
        written = carried.appended_to(written)
    if recording is not None:  # the input's column order, with or without a model (as the service writes it)
        written = in_order(written, recording.names)
    stage(f"writing {output}")
    write_labeled(output, written, source, start or 0)
    summary = track_summary(capture, result, windows, labeling.formulation.name, time.perf_counter() - began, output)
    summary["second_pass"] = None if labeling.choice is None else labeling.choice.to_dict()
    summary["rival_reading"] = None if labeling.rival is None else labeling.rival.to_dict()
    summary["mht_reading"] = None if labeling.hypotheses is None else labeling.hypotheses.to_dict()
    summary["exchanged_back"] = exchange_summary(labeling.exchanges, capture.names)
    summary["handed_back"] = handover_summary(labeling.handovers, capture.names)
    summary["shape_breaks"] = shape_break_summary(labeling.shape_breaks, result.names)
    summary["model_misfits"] = [asdict(misfit) for misfit in labeling.model_misfits]
    if as_json:
        print(json.dumps(summary, allow_nan=False))
    else:
        out.print(
            f"{input.name}: {summary['markers']} markers x {summary['frames']} frames ({capture.mode}) -> {output} "
            f"({summary['occluded_fraction']:.1%} occluded, {summary['integral_window_fraction']:.0%} windows "
            f"{CERTIFICATE}, max gap {max((w.gap for w in windows), default=0.0):.1e}, "
            f"{summary['doubtful_fraction']:.1%} labels doubtful, noise {_mm(summary['noise_mm'])})"
            f"{second_pass_note(labeling.choice)}{rival_note(labeling.rival)}"
            f"{rival_note(labeling.hypotheses, 'an mht reading', options.mht_reading)}"
            f"{_exchange_note(len(labeling.exchanges), len(labeling.handovers))}"
            f"{leftover_note(summary, output.suffix.lower() == '.c3d')}",
            highlight=False,
        )
    for line in labeling.warnings(result, windows, unit, start or 0, spacing_judged=True):
        warn(line)
    warn(not_kept)
    warn(absent_warning(absent, start or 0))
    warn(_unknown_warning(unknown, start or 0))


def track_summary(
    capture: Capture, result: LabeledTrajectories, windows: list[WindowStats], formulation: str, seconds: float,
    output: Path,
) -> dict[str, Any]:
    """The figures ``markerflow track --json`` prints: size, occluded share, certificate, doubt, noise, time.

    ``certificate`` says what an integral window proves: optimal under the model, not
    right; or, when no window has a bound (a frame-by-frame or greedy formulation), that
    none does. ``doubtful_fraction`` and ``reacquired`` (marker -> frames) are those of
    ``service.labeling.stats``, ``lone_labels`` (marker -> frames seen alone amid an occlusion,
    doubtful) of ``service.labeling.reported``. ``noise_mm`` is the take's measurement noise read back
    from the labeled positions (``TakeNoise``: the robust scale of the constant-acceleration
    residual, mean over the axes); None when too little was seen to say. ``fast_markers``
    lists the markers that move more per frame than half their neighbour distance
    (``service.labeling.take_warnings``: marker, step_mm, neighbour_mm, neighbour);
    ``coincident_markers`` the pairs of markers on one position, copied columns
    (``service.labeling.coincident``).
    ``unnamed_span`` is the longest stretch where no marker is labeled though points are
    there (``service.labeling.lost_subject``: start, frames, points), or None.
    ``unlabeled_points``, ``unlabeled_trajectories`` and ``unlabeled_copies``: what ``service.labeling.leftover_points`` kept.
    ``run_track`` adds ``second_pass`` (``PassChoice``: each pass's doubtful share, its
    rigid pairs' disagreement with the first frame, and the one kept), None when no second
    pass applied; ``rival_reading`` (``RivalChoice``: the window and frame-by-frame readings'
    disagreement with the first frame, and the markers taken from the latter), None when it did
    not run; ``mht_reading`` likewise for the ``mht`` reading after it (``hypothesis_reading``);
    ``exchanged_back``, the pairs whose labels the first frame's shape gave
    back over the take (``service.labeling.exchanged``: markers, frames from 0 [start, stop));
    ``handed_back``, the tracks given back to the marker they continue (owner, taker, frames);
    and ``shape_breaks``, the labels that left their rigid neighbours (``service.labeling.shape_doubt``).
    """
    noise = TakeNoise.of(result.positions) if _has_runs(result.positions) else None
    return {
        "frames": capture.n_frames,
        "markers": len(capture.names),
        "mode": capture.mode,
        "occluded_fraction": float(result.occluded.mean()),
        "noise_mm": None if noise is None else finite_or_none(float(noise.measurement_mm.mean())),
        **certificate_figures(windows),
        "certificate": CERTIFICATE if any(w.integral or np.isfinite(w.gap) for w in windows) else NO_CERTIFICATE,
        "doubtful_fraction": doubtful_fraction(result.confidence, result.occluded),
        "reacquired": reacquisitions(result.names, result.occluded),
        "lone_labels": lone_sightings(result.names, result.occluded),
        "fast_markers": [vars(fast) for fast in fast_markers(result.names, result.positions)],
        "coincident_markers": [list(pair) for pair in coincident_pairs(result.names, result.positions)],
        "unnamed_span": _unnamed(capture, result),
        **leftover_summary(result),
        "seconds": seconds,
        "formulation": formulation,
        "output": str(output),
    }


def _exchange_note(exchanges: int, handovers: int) -> str:
    """What the summary line says of pairs the first frame's shape gave back, and of tracks
    handed back to the marker they continue (``exchanged``)."""
    said = []
    if exchanges:
        said.append(f"{exchanges} exchanged pair{'s' if exchanges > 1 else ''} given back by the first frame's shape")
    if handovers:
        said.append(f"{handovers} tracks handed back to the markers they continue" if handovers > 1
                    else "1 track handed back to the marker it continues")
    return f"; {', '.join(said)} (labels doubtful)" if said else ""


def _unnamed(capture: Capture, result: LabeledTrajectories) -> dict[str, Any] | None:
    if capture.points is None:  # camera mode: no count of points per frame to hold the labels against
        return None
    span = unnamed_span(result.occluded, np.array([len(p) for p in capture.points]), capture.rate)
    return None if span is None else vars(span)


def _unknown_warning(unknown: list[str], start: int) -> str | None:
    """The markers labeled at ``start`` that the model lacks and no posed segment could measure
    (``labeled_singles``): labeling from the model does not name them; the output carries the
    input's samples under their names (``carried_markers``)."""
    if not unknown:
        return None
    return (f"warning: {counted(len(unknown), 'marker')} labeled at frame {start} not in the model, not labeled "
            f"(written as the input has them): {', '.join(unknown[:12])}{' ...' if len(unknown) > 12 else ''} "
            "(fit the model on frames where they are seen, or label without --model)")


def _has_runs(positions: np.ndarray, order: int = 3) -> bool:
    """Some marker was seen ``order + 1`` frames in a row: the noise has a residual to be read from."""
    return bool(np.isfinite(np.diff(positions, n=order, axis=0)).any())


def _mm(value: object) -> str:
    return "unknown" if value is None else f"{value:.2f} mm"


def _read_input(
    input: Path, shuffle: bool, span: tuple[int | None, int | None] | None = None,
) -> tuple[Capture, LabelingOptions, Recording | None, list[str]]:
    """The capture, its options, the recording read (its ``source`` is what output written
    from it keeps; none for JSON), and the markers left out because they are absent in its
    labeled frame.

    ``span`` (start, end) relabels a recording from its own labels: at ``start``
    (``capture_from_span``: markers absent there are left out), or when no start is given at
    frame 0, which must then have every marker. None (a subject model names the markers):
    the whole input, as read. A capture JSON takes an end but no start: its labels are of frame 0.
    """
    start, end = span or (None, None)
    if input.suffix.lower() != ".json":
        recording = read_labeled(input)
        if recording.n_frames < 2:  # said here, where the file is known
            raise InputError(f"{input.name}: the take has {recording.n_frames} frame; labeling needs at least 2")
        if span is None:
            return capture_from_recording(recording, shuffle), LabelingOptions(), recording, []
        if start is None:
            require_complete_first_frame(recording, input.name)
        capture, absent = capture_from_span(recording, start or 0, end, shuffle)
        return capture, LabelingOptions(), recording, absent
    if start:
        raise InputError("--start of a capture JSON needs --model: its labels are of frame 0 only")
    try:
        text = input.read_bytes()
    except OSError as error:
        raise InputError(f"{input}: cannot read ({error.strerror})") from None
    document = read_capture_document(text, str(input))
    try:  # the checks of the capture itself (frame 0 against the calibration) name the file as the document's do
        capture = document.capture()
    except InputError as error:
        raise InputError(f"{input}: {error}") from None
    return _until(capture, end), document.options(), None, []


def _until(capture: Capture, end: int | None) -> Capture:
    """The capture's frames 0 .. ``end`` - 1 (all of them without ``end``): its labels are of frame 0."""
    if end is None:
        return capture
    stop = frame_span(0, end, capture.n_frames)
    if capture.points is not None:
        return replace(capture, points=capture.points[:stop])
    return replace(capture, detections=(capture.detections or [])[:stop])


def _kept(source: SourceFile | None, names: list[str], output: Path) -> tuple[SourceFile | None, str | None]:
    """What output from a model keeps of its input (``kept_source``); and, for a .c3d output
    that then loses the input's other content, the warning that says so."""
    kept, lacking = kept_source(source, names)
    if not lacking:
        return kept, None
    warning = (f"warning: the input has no point for model markers {', '.join(lacking[:6])}"
               f"{' ...' if len(lacking) > 6 else ''}, so {output.name} is a new C3D of the labels and the input's "
               "other markers (its unit and frame numbering, but not its analog channels, events or other parameters)")
    return kept, warning if output.suffix.lower() == ".c3d" else None


def _formulation_table(spec: str) -> str | dict:
    """A name stays a name; a TOML preset becomes its ``[formulation]`` table."""
    return formulation_table(Path(spec)) if spec.lower().endswith(".toml") else spec
