"""What a finished labeling warns of, one line each: the lines ``markerflow track`` prints
after its summary, and a job's status and page show once it is done.

An integral window is optimal under the model, not proven right: a take whose labels are
mostly doubtful or mostly occluded, whose labels leave the shape of their rigid neighbours, whose markers move
further per frame than they are apart, whose plates no distance tells apart, that is not
human-sized in its unit, has copied columns, or where no marker is labeled though points are
there, is labeled wrongly in ways the certificate does not see. These lines say so.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.shape_breaks import ShapeBreak
from formulations.solvers.base import stopped_by_time
from service.capture.capture import Capture
from service.capture.reprojection import frame0_offsets, frame0_problem
from service.io.recording import LabeledTrajectories
from service.labeling.coincident import coincident_pairs, coincident_warning
from service.labeling.lost_subject import away_span, away_warning, unnamed_span, unnamed_warning
from service.labeling.shape_doubt import shape_break_warning
from service.labeling.stats import DOUBTFUL_WARNING, REPORTED_DOUBTFUL_BELOW, doubtful_fraction
from service.labeling.symmetric_plates import symmetric_plate_warning, symmetric_plates
from service.labeling.take_warnings import fast_markers, fast_motion_warning, scale_warning, spacing_frame
from service.labeling.triangulated_scale import triangulated_scale_warning

# Named from a model alone, a take is mostly doubtful when the model is of someone else: CMU
# 85_02's subject's model on 135_02 gave 40 % doubtful labels, 77 % of them wrong (its own: 0 %).
MODEL_ADVICE = "check them, and that the model is of this subject and marker set"


def time_limit_warning(statuses: list[str]) -> str | None:
    """A line when some windows' solves stopped at the formulation's time limit: their labels
    are the best found in time, not proven (a limit of 1 us left 85_02 under the hard scenario
    59.5 % right, without a word)."""
    stopped = sum(stopped_by_time(status) for status in statuses)
    if not stopped:
        return None
    return (f"warning: {stopped} of {len(statuses)} windows stopped at the solver's time limit: their labels are the "
            "best found in time, not proven (raise the formulation's time_limit)")


def early_scale_warning(capture: Capture, unit: str) -> str | None:
    """The marker spacing's line, before labeling: of the labeled first frame, or of frame 0's
    points when a subject model is to name them."""
    first = spacing_frame(capture.first_frame, capture.points)
    labeled = np.asarray(capture.first_frame, dtype=float).reshape(-1, 3)
    named = np.isfinite(labeled).all(axis=1).sum() >= 2  # else ``first`` is frame 0's points, unnamed
    return scale_warning(first, first[None], capture.rate, unit, names=list(capture.names) if named else None)


def doubtful_warning(fraction: float | None, advice: str = "check them") -> str | None:
    """A line when more than ``DOUBTFUL_WARNING`` of the labels are doubtful, ending ``advice``."""
    if fraction is None or fraction <= DOUBTFUL_WARNING:
        return None
    return (f"warning: {fraction:.1%} of the labels are doubtful (confidence below {REPORTED_DOUBTFUL_BELOW:.1%}: "
            f"another reading of their window is nearly as likely, or the marker was seen alone amid an occlusion); {advice}")


OCCLUDED_WARNING = 0.5  # warn when more than this share of the marker-frames after the labeled one took nothing


def occluded_warning(occluded: np.ndarray) -> str | None:
    """A line when most marker-frames after the labeled frame are occluded: a camera take with
    no detection after frame 0 came back 99.3 % occluded with nothing said but the summary."""
    later = np.asarray(occluded)[1:]
    share = float(later.mean()) if later.size else 0.0
    if share <= OCCLUDED_WARNING:
        return None
    return (f"warning: {share:.1%} of the marker-frames after the labeled frame are occluded (no point or detection "
            "taken): check that the input holds the markers in those frames")


def result_warnings(capture: Capture, result: LabeledTrajectories, breaks: list[ShapeBreak], unit: str = "mm",
                    start: int = 0, spacing_judged: bool = False) -> list[str]:
    """Every line that applies to ``result``, the labeling of ``capture`` (whose input was in
    ``unit``, its labels starting at input frame ``start``) with its ``breaks`` (``shape_doubt``);
    ``spacing_judged``: the marker spacing was judged before labeling (``early_scale_warning``),
    so only the speed is."""
    fraction = doubtful_fraction(result.confidence, result.occluded) if result.confidence.size else None
    identified = capture.model is not None and not np.isfinite(np.asarray(capture.first_frame, dtype=float)).any()
    first = np.asarray(capture.first_frame, dtype=float).reshape(-1, 3)
    lines = [
        occluded_warning(result.occluded),
        doubtful_warning(fraction, MODEL_ADVICE if identified else "check them"),
        shape_break_warning(breaks, result.names, start),
        fast_motion_warning(fast_markers(result.names, result.positions)),
        scale_warning(first, result.positions, capture.rate, unit, spacing=not spacing_judged, names=list(capture.names)),
        coincident_warning(coincident_pairs(result.names, result.positions)),
        symmetric_plate_warning(symmetric_plates(list(result.names), result.positions, first)),
    ]
    if capture.points is not None:  # camera mode has no count of points per frame to hold the labels against
        counts = np.array([len(p) for p in capture.points])
        lines.append(unnamed_warning(unnamed_span(result.occluded, counts, capture.rate), capture.rate, start))
        lines.append(away_warning(away_span(result.occluded, counts, capture.rate), capture.rate, start))
    else:  # camera mode: a camera whose calibration or detections are off at frame 0, or every camera's focal length
        problem = frame0_problem(capture.camera_frames()[0], frame0_offsets(capture.frame0_distances()))
        lines += [problem[1] if problem is not None else None, triangulated_scale_warning(result.positions)]
    return [line for line in lines if line is not None]
