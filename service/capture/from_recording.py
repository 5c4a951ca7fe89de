"""A labeled recording as a capture to relabel: one frame labeled, every frame's points unnamed.

``markerflow track`` and the HTTP upload of a C3D/TRC both label a recording this way, so
they give the same answer for the same file.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from service.capture.capture import Capture
from service.capture.span import frame_span
from service.errors import InputError
from service.io.recording import Recording


def capture_from_recording(recording: Recording, shuffle: bool = True, seed: int = 0) -> Capture:
    """Each frame's present points without their labels; the recording's frame 0 labeled.

    Missing samples (NaN, or (0, 0, 0)) are dropped; the fixed seed makes the shuffle,
    and so the labeling, a function of the file alone. Unlabeled trajectories (``*N``,
    ``is_unlabeled``) are not markers: only their points are in the frames.
    """
    rng = np.random.default_rng(seed)
    present = ~recording.missing()
    frames = []
    for f in range(recording.n_frames):
        points = recording.positions[f][present[f]]
        frames.append(points[rng.permutation(len(points))] if shuffle else points)
    markers = recording.without_unlabeled()
    return Capture(list(markers.names), markers.positions[0], recording.rate, points=frames)


def capture_from_span(
    recording: Recording, start: int, end: int | None = None, shuffle: bool = True, seed: int = 0,
) -> tuple[Capture, list[str]]:
    """Frames ``start .. end - 1`` of ``recording`` labeled from its frame ``start``, and the
    names of the markers absent there, which the capture leaves out.

    Their points stay in the frames, unnamed (a relabel throws every label away): a marker
    with no position in the labeled frame has nothing to start its track from.

    Raises:
        InputError: A span outside the take (``frame_span``), no marker named (only unlabeled
            trajectories), or no marker present at ``start``.
    """
    stop = frame_span(start, end, recording.n_frames)
    markers = recording.without_unlabeled()
    if not markers.names:
        raise InputError(f"no marker is named: its {recording.n_markers} points are all unlabeled trajectories (*N); "
                         "--model names them from a subject model (without --keep-labels: there are no labels to keep)")
    present = ~markers.missing()[start]
    if not present.any():
        raise InputError(f"--start {start}: no marker is labeled in that frame{_hint(markers)}")
    span = capture_from_recording(Recording(recording.names, recording.positions[start:stop], recording.rate),
                                  shuffle, seed)
    names = [n for n, p in zip(span.names, present) if p]
    absent = [n for n, p in zip(span.names, present) if not p]
    return replace(span, names=names, first_frame=span.first_frame[present], unnamed_markers=len(absent)), absent


def require_complete_first_frame(recording: Recording, source: str, start: str = "--start ", more: str = "") -> None:
    """Refuse a recording whose frame 0 lacks a marker, pointing at the ``start`` option
    (``--start `` on the command line, ``start=`` in a service upload), then ``more``.

    Raises:
        InputError: A marker is missing in frame 0; the line names it and the fullest frame.
    """
    markers = recording.without_unlabeled()
    absent = np.flatnonzero(markers.missing()[0])
    if len(absent):
        raise InputError(
            f"{source}: marker '{markers.names[absent[0]]}' has no position in the first frame "
            f"({len(absent)} of {markers.n_markers} absent); {_start_hint(markers, start)}{more}"
        )


def _start_hint(recording: Recording, start: str) -> str:
    """Which ``start`` to give: the fullest frame, or, when frame 0 is as full as any, that
    ``start`` 0 labels from it; and a marker no frame has, if any."""
    best, count = recording.fullest_frame()
    if count == 0:
        return "no frame has a marker's position: the take holds no point to label"
    if best == 0:
        hint = (f"no frame has all {recording.n_markers}: {start}0 labels from frame 0, the absent markers "
                "written missing")
    else:
        hint = f"{start}{best} labels from the frame with the most ({count} of {recording.n_markers})"
    never = recording.without_never_seen()[1]
    return hint + (f"; {never[0]} has no position in any frame" if never else "")


def _hint(recording: Recording) -> str:
    """Where the take's labels are fullest: the frame a user would start from."""
    best, count = recording.fullest_frame()
    return f" (frame {best} has the most markers labeled: {count} of {recording.n_markers})"
