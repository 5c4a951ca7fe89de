"""A doubtful take read once more by the multiple-hypothesis tracker, and merged as the
frame-by-frame reading is.

When a lost marker comes back beside another lost marker of its segment, the window LP and
the frame-by-frame assignment can make the same exchange: both judge the return by the same
costs, from the same stale shape and prediction. The multiple-hypothesis tracker (``mht``,
Ringer & Lasenby 2002: I readings of the window kept frame by frame, each expanded by its J
best assignments, cut to the cheapest as the frames come) solves the same windows and often
keeps the two apart. CMU 135_02 under the hard preset (10 ghosts a frame, 30 % deletions in
60-frame bursts, 4 mm noise), seed 1: LWRA, unseen for over 100 frames, takes LFIN's returning
point at frame 161 in both window passes and in the frame-by-frame reading, and holds it to the
end of the take (95.58 % right); ``mht`` keeps them apart (100 %). (So it was while a lost
marker's one-frame sightings moved its state; since they do not, the windows keep that pair
apart too, 99.99 %.)

Neither it nor the others are right everywhere, so it is one reading more, not a replacement
(in place of the frame-by-frame reading it took the real basket sprint from 92.17 to 83.57 %):
read with its own second pass as the frame-by-frame reading is
(``rival_reading.read_frame_by_frame``) and merged after it, event by event, by the same judge
(``rival_reading.merged_with_rival``: the labeled first frame's rigid pairs). Asked for
(``LabelingOptions.mht_reading``, ``track --mht-reading``; off by default, as it makes a
doubtful take about 1.7 times slower even in a process of its own, ``rival_process``), it
runs where the frame-by-frame reading runs, on 3D points without a subject model (where it
was measured), and not when the windows are ``mht``'s own (``unread_reason``).
"""

from __future__ import annotations

from formulations.markers.state import MarkerState
from formulations.methods.formulation import Formulation
from formulations.methods.mht import Mht
from service.capture.capture import Capture, LabelingOptions
from service.labeling.associations import association_chain
from service.labeling.outcome import WindowOutcome
from service.labeling.rival_reading import RivalChoice, RivalReading, merged_with_rival, rival_unread_reason
from service.labeling.second_pass import Labels, judged_part


def hypothesis_reading(
    capture: Capture, options: LabelingOptions, formulation: Formulation, labels: Labels,
) -> RivalReading | None:
    """The ``mht`` reading of a capture whose frame-by-frame reading runs (so 3D points), when
    ``options.mht_reading`` asks for it, the capture has no subject model and the windows are not
    ``mht``'s already; else None. ``labels`` gives a reading's labels as the merge takes them (no
    take-wide repair): the kept windows' as well as its own."""
    if not options.mht_reading or unread_reason(capture, options, formulation) is not None:
        return None
    return RivalReading(association_chain(capture, options, look_ahead=True), Mht(), labels)


def unread_reason(capture: Capture, options: LabelingOptions, formulation: Formulation) -> str | None:
    """Why the ``mht`` reading never runs on ``capture`` with ``options`` and ``formulation`` (a
    clause for an error line), or None: then it runs wherever the take is doubtful enough for a
    second pass (where the frame-by-frame reading runs, ``rival_unread_reason``)."""
    if capture.model is not None:
        return "it reads takes without a subject model"
    if isinstance(formulation, Mht):
        return "the windows are mht's own"
    return rival_unread_reason(capture, options, formulation)


def merged_with_hypotheses(
    reading: RivalReading, first: MarkerState, kept: list[WindowOutcome], read: list[WindowOutcome],
) -> tuple[list[WindowOutcome], RivalChoice]:
    """``kept`` with the marker groups the ``mht`` reading labels better taken from it, and what
    was taken.

    Args:
        reading: From ``hypothesis_reading``.
        first: The labeled first frame's state.
        kept: The windows kept so far (after the second pass and the frame-by-frame reading),
            assembled as ``reading.labels`` assembles a reading's.
        read: The ``mht`` reading's windows (``rival_reading.read_frame_by_frame`` of ``reading``;
            in a child process beside the others on a large take, ``rival_process``).
    """
    return merged_with_rival(reading, first, kept, judged_part(reading.labels(kept)), read)
