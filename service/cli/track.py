"""``markerflow track``: label a capture JSON, or relabel a recording from its first frame."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from formulations.markers.noise import TakeNoise
from service.capture.capture import Capture, LabelingOptions
from service.capture.document import read_capture_document
from service.capture.formulation_spec import formulation_table
from service.capture.from_recording import capture_from_recording
from service.cli.output import check_writable_output
from service.cli.report import out, window_progress
from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.stats import WindowStats, certificate_figures, finite_or_none


def run_track(
    input: Path, output: Path, formulation: str | None, window: int | None, shuffle: bool, as_json: bool = False,
) -> None:
    """Label ``input`` (capture .json, or labeled .c3d/.trc/.csv) and write ``output``.

    ``formulation`` and ``window`` override a JSON document's own options when given.
    Prints one line, or with ``as_json`` one JSON object (``track_summary``), on stdout.
    """
    check_writable_output(output)
    capture, options = _read_input(input, shuffle)
    if formulation is not None:
        options = replace(options, formulation=_formulation_table(formulation))
    if window is not None:
        options = replace(options, window=window)
    labeling = CaptureLabeling(capture, options)
    began = time.perf_counter()
    with window_progress(f"labeling {input.name}") as progress:
        result, windows = labeling.label(progress)
    write_labeled(output, result)
    summary = track_summary(capture, result, windows, labeling.formulation.name, time.perf_counter() - began, output)
    if as_json:
        print(json.dumps(summary, allow_nan=False))
        return
    out.print(
        f"{input.name}: {summary['markers']} markers x {summary['frames']} frames ({capture.mode}) -> {output} "
        f"({summary['occluded_fraction']:.1%} occluded, {summary['integral_window_fraction']:.0%} windows integral, "
        f"max gap {max((w.gap for w in windows), default=0.0):.1e}, noise {_mm(summary['noise_mm'])})",
        highlight=False,
    )


def track_summary(
    capture: Capture, result: LabeledTrajectories, windows: list[WindowStats], formulation: str, seconds: float,
    output: Path,
) -> dict[str, float | int | str | None]:
    """The figures ``markerflow track --json`` prints: size, occluded share, certificate, noise, time.

    ``noise_mm`` is the take's measurement noise read back from the labeled positions
    (``TakeNoise``: the robust scale of the constant-acceleration residual, mean over the
    axes); None when too little was seen to say.
    """
    noise = TakeNoise.of(result.positions) if _has_runs(result.positions) else None
    return {
        "frames": capture.n_frames,
        "markers": len(capture.names),
        "mode": capture.mode,
        "occluded_fraction": float(result.occluded.mean()),
        "noise_mm": None if noise is None else finite_or_none(float(noise.measurement_mm.mean())),
        **certificate_figures(windows),
        "seconds": seconds,
        "formulation": formulation,
        "output": str(output),
    }


def _has_runs(positions: np.ndarray, order: int = 3) -> bool:
    """Some marker was seen ``order + 1`` frames in a row: the noise has a residual to be read from."""
    return bool(np.isfinite(np.diff(positions, n=order, axis=0)).any())


def _mm(value: object) -> str:
    return "unknown" if value is None else f"{value:.2f} mm"


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
