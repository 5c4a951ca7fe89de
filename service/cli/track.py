"""``markerflow track``: label a capture JSON, or relabel a recording from its first frame."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from service.capture.capture import Capture, LabelingOptions
from service.capture.document import read_capture_document
from service.capture.formulation_spec import formulation_table
from service.capture.from_recording import capture_from_recording
from service.cli.report import out, window_progress
from service.errors import InputError
from service.io.formats import check_output, read_labeled, write_labeled
from service.labeling.capture_labeling import CaptureLabeling


def run_track(input: Path, output: Path, formulation: str | None, window: int | None, shuffle: bool) -> None:
    """Label ``input`` (capture .json, or labeled .c3d/.trc/.csv) and write ``output``.

    ``formulation`` and ``window`` override a JSON document's own options when given.
    """
    check_output(output)
    capture, options = _read_input(input, shuffle)
    if formulation is not None:
        options = replace(options, formulation=_formulation_table(formulation))
    if window is not None:
        options = replace(options, window=window)
    labeling = CaptureLabeling(capture, options)
    with window_progress(f"labeling {input.name}") as progress:
        result, windows = labeling.label(progress)
    write_labeled(output, result)
    integral = np.mean([w.integral for w in windows]) if windows else 1.0
    out.print(
        f"{input.name}: {len(capture.names)} markers x {capture.n_frames} frames ({capture.mode}) -> {output} "
        f"({result.occluded.mean():.1%} occluded, {integral:.0%} windows integral, "
        f"max gap {max((w.gap for w in windows), default=0.0):.1e})"
    )


def _read_input(input: Path, shuffle: bool) -> tuple[Capture, LabelingOptions]:
    if input.suffix.lower() != ".json":
        return capture_from_recording(read_labeled(input), shuffle), LabelingOptions()
    try:
        text = input.read_bytes()
    except OSError as error:
        raise InputError(f"{input}: cannot read ({error.strerror})") from None
    document = read_capture_document(text, str(input))
    return document.capture(), document.options()


def _formulation_table(spec: str) -> str | dict:
    """A name stays a name; a TOML preset becomes its ``[formulation]`` table."""
    return formulation_table(Path(spec)) if spec.endswith(".toml") else spec

