"""A doubtful take read again frame by frame, and the two readings merged event by event.

A window of frames sums a lost marker's one costly return with the cheap steps after it. When
the marker's rigid neighbours were lost with it, its shape and prediction are stale, and the
window may give it the track of another lost marker coming back near it; every later window
inherits the exchange. A frame-by-frame assignment (``nn-hungarian``: the same candidates and
costs, no later frame seen) decides each frame on that frame's evidence and often keeps the two
apart. On the real 03_rolling from frame 562 (one pass each) the window reading labels 75.3 %
of its named markers' samples right and the frame-by-frame one 86.9 %; on the seed-0 accuracy
matrix the window reading (one pass) is at or above it on 71 of 85 rows. Neither is right
everywhere, so a take doubtful enough for a second pass (``second_pass``) is read frame by
frame as well (with its own second pass, as ``nn-hungarian`` labels a take), and the readings
are merged as the passes are (``formulations.markers.pass_merge``): the labels they give
differently fall into events that share no point, and each event takes the frame-by-frame
labels only where they bend its rigid pairs clearly less off the labeled first frame
(``first_frame_shape``), or, on a near tie, where they bend the markers' group less over the
whole take. The windows and their certificates stay the window reading's; the markers taken
are counted in the choice (``RivalChoice``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.markers.first_frame_handedness import first_frame_judges
from formulations.markers.first_frame_shape import disagreement
from formulations.markers.pass_merge import labels_taken
from formulations.markers.state import MarkerState
from formulations.methods.formulation import Formulation
from service.capture.capture import Capture, LabelingOptions
from service.io.recording import LabeledTrajectories
from service.labeling.loop import Progress, WindowChain, label_windows, progress_after
from service.labeling.outcome import WindowOutcome
from service.labeling.second_pass import Labels, Stop, judged_part, merged_readings, second_pass


@dataclass(frozen=True)
class RivalReading:
    """How a take is read frame by frame: the chain (gated without look-ahead), the formulation,
    and its labels as a frame-by-frame labeling gives them (no take-wide repair: they look ahead)."""

    chain: WindowChain
    formulation: Formulation
    labels: Labels


@dataclass(frozen=True)
class RivalChoice:
    """What the frame-by-frame reading changed.

    Attributes:
        window_off_mm, rival_off_mm: Each reading's disagreement with the first frame's rigid
            pairs (mm; ``first_frame_shape.disagreement``), None where no pair is labeled.
        markers: Markers whose labels come from the frame-by-frame reading.
    """

    window_off_mm: float | None
    rival_off_mm: float | None
    markers: int

    def to_dict(self) -> dict:
        return {"window_off_mm": self.window_off_mm, "rival_off_mm": self.rival_off_mm, "markers": self.markers}


def rival_unread_reason(capture: Capture, options: LabelingOptions, formulation: Formulation) -> str | None:
    """Why the frame-by-frame reading (and so the ``mht`` reading after it) never runs on
    ``capture`` with ``options`` and ``formulation`` (a clause for an error line), or None: then
    it runs wherever the take is doubtful enough for a second pass."""
    if capture.points is None:
        return "the readings are of 3D points, and this take is camera detections"
    if not options.second_pass:
        return "the readings run after the second pass, which is off"
    if not options.rival_reading:
        return "the frame-by-frame reading is off"
    if not formulation.look_ahead:
        return f"the windows ({formulation.name}) are read frame by frame already"
    return None


def read_frame_by_frame(
    rival: RivalReading, first: MarkerState, frames: int, window: int, progress: Progress | None = None,
    stop: Stop | None = None,
) -> list[WindowOutcome] | None:
    """The take's windows read frame by frame, with their own second pass; None when ``stop``
    asked to abandon the reading. Needs nothing of the window reading: ``rival_process`` runs
    it beside that reading's second pass.

    Args:
        rival: The frame-by-frame chain and formulation.
        first, frames, window: As the take was labeled (``first``: the labeled first frame's state).
    """
    read: list[WindowOutcome] = []
    for outcome in label_windows(rival.chain, rival.formulation, first, frames, window, None, progress):
        read.append(outcome)
        if stop is not None and stop():
            return None
    # Its own second pass as well, as a frame-by-frame labeling runs: on the seed-0 matrix's 85
    # rows, one pass judged with the take-wide repairs gave 97.801 % against 97.930 %; on four
    # cells one pass alone lost too (03_rolling at 4 mm 84.5 against 88.5 %, BTS at 4 mm 96.4 against 99.0 %).
    passes = second_pass(rival.chain, rival.formulation, first, frames, window, read, rival.labels,
                         progress_after(progress, len(read)), stop)
    return None if passes is None else passes[0]


def merged_with_rival(
    rival: RivalReading, first: MarkerState, kept: list[WindowOutcome], labels: LabeledTrajectories,
    read: list[WindowOutcome],
) -> tuple[list[WindowOutcome], RivalChoice]:
    """``kept`` with the marker groups the frame-by-frame reading ``read`` labels better taken
    from it (module doc), each label's confidence judged with the other reading's
    (``merged_readings``), and what was taken.

    Args:
        rival: The frame-by-frame reading (its ``labels``).
        first: The labeled first frame's state.
        kept: The windows kept so far (after the second pass).
        labels: ``kept``'s labels, tracks extended but not repaired (the merge takes window
            columns; ``judged_part`` is enough): assembled while the reading runs beside
            (``rival_process``).
    """
    mine, theirs = judged_part(labels), judged_part(rival.labels(read))
    capped, judged, flips = first_frame_judges([mine.positions, theirs.positions], first.position, first.neighbours)
    # Ties stay with the window reading: its windows, certificates and look-ahead.
    taken = labels_taken((mine.point_index, theirs.point_index), capped, judged, flips=flips)
    window_off, rival_off = (None if np.isnan(v) else float(v) for v in disagreement(capped, judged))
    choice = RivalChoice(window_off, rival_off, int(taken.any(axis=0).sum()))
    return merged_readings(kept, read, taken), choice
