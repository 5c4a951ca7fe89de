"""A capture labeled from a subject model instead of a labeled first frame."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from formulations.errors import FormulationError
from formulations.subject.geometry import ModelGeometry
from formulations.subject.labeled_singles import with_labeled_singles
from formulations.subject.model import SubjectModel
from service.capture.capture import Capture
from service.capture.span import frame_span
from service.errors import InputError
from service.io.recording import is_unlabeled

MIN_SHARED = 0.5  # of a labeled take's names the model must know: less is another marker set


def read_model(path: Path) -> SubjectModel:
    """The subject model JSON at ``path``. Raises ``InputError`` (one line) when unreadable or not a model."""
    try:
        text = path.read_text()
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (a subject model is JSON)") from None
    return parse_model(text, str(path))


def parse_model(text: str, source: str) -> SubjectModel:
    try:
        model = SubjectModel.from_json(text)
        ModelGeometry.of(model)
    except (FormulationError, ValueError) as error:
        raise InputError(f"{source}: {error}") from None
    return model


def model_names(model: SubjectModel) -> list[str]:
    """The markers the model names, in the order labels come out: segments' in order, then singles."""
    return ModelGeometry.of(model).names


def check_shared_names(take: list[str], model: SubjectModel, source: str) -> None:
    """A labeled take must be of the model's marker set (model markers the take lacks are normal).

    Raises:
        InputError: Fewer than half of the take's names are the model's; the line lists them.
    """
    known = set(model_names(model))
    take = [name for name in take if not is_unlabeled(name)]  # *N: points for the model to name, no marker
    shared = [name for name in take if name in known]
    if len(shared) < MIN_SHARED * len(take):
        foreign = [name for name in take if name not in known]
        folded = {name.casefold() for name in known}
        case = sum(name.casefold() in folded for name in foreign)
        hint = f"; {case} differ from the model's only in upper/lower case" if case else ""
        raise InputError(
            f"{source}: only {len(shared)} of its {len(take)} markers are in the model "
            f"(not in it: {', '.join(foreign[:12])}{' ...' if len(foreign) > 12 else ''}{hint})"
        )


def with_model(
    capture: Capture, model: SubjectModel, start: int = 0, end: int | None = None, keep_labels: bool = False,
) -> Capture:
    """The capture's frames ``start .. end - 1`` (3D points) under the model's names, frame ``start``
    unlabeled; with ``keep_labels`` (and ``start`` 0) the capture's labeled first frame is kept,
    markers the model lacks added to it as singles measured there, and the model names the
    rest. Until it does, their points are unnamed tracks that labeled markers do not take
    (``Capture.unnamed_markers``, unless the capture says how many). Second halves of the real
    takes lacking a marker in frame 0, from their middle frame's labels and a model of the
    first half, with them / without: 03_rolling (600 frames) 78.57 / 59.85 %, basket sprint
    88.06 / 85.03 %, racing 85.26 / 80.48 %, BTS 74.99 / 74.72 %.

    Raises:
        InputError: A camera capture, or an empty or out-of-range span.
    """
    if capture.points is None:
        raise InputError("labeling from a subject model needs 3D points (camera mode needs a labeled first frame)")
    stop = frame_span(start, end, capture.n_frames)
    kept = keep_labels and start == 0
    labeled = np.asarray(capture.first_frame, dtype=float).reshape(-1, 3)
    if kept and capture.names:  # labeled markers the model lacks become singles of it (``labeled_singles``)
        model = with_labeled_singles(model, capture.names, labeled)
    names = model_names(model)
    first = np.full((len(names), 3), np.nan)
    unnamed = capture.unnamed_markers
    if kept:
        for row, name in enumerate(capture.names):
            if name in names:
                first[names.index(name)] = labeled[row]
        if capture.names:  # and the labeled markers still lacking (nothing posed): their points are never named
            unnamed = (unnamed or int(np.isnan(first).any(axis=1).sum())) + sum(n not in names for n in capture.names)
    return replace(capture, names=names, first_frame=first, points=capture.points[start:stop], model=model,
                   unnamed_markers=unnamed)
