"""``markerflow boxes``: track MOTChallenge detections of one camera, write a result file."""

from __future__ import annotations

import json
from pathlib import Path

from formulations.boxes.lifecycle import Lifecycle
from service.boxes.frames import box_histograms, frame_size
from service.boxes.image_checks import normalised_warning, outside_image_warning
from service.boxes.mot_files import read_detections, read_seqinfo, write_tracks
from service.boxes.track import track_boxes
from service.capture.formulation_spec import formulation_from_spec
from service.cli.output import check_writable_output
from service.cli.report import out, warn
from service.errors import InputError

TUNED_WINDOW = 5  # the default --window, the one the box costs were chosen at (docs/boxes.md)
UNTRACKED_WARNING = 0.25  # detections in no track, past a longer window: objects were dropped


def long_window_warning(window: int, detections: int, tracked: int) -> str | None:
    """A line when a window longer than the tuned one left many detections in no track: the
    window prices each of its frames against the template's forecast, so far frames of a long
    window lose people who change pace (MOT17-02's first 60 frames: 687 of 687 boxes tracked
    at window 5, 609 at 20, 380 at 30)."""
    untracked = 1 - tracked / detections if detections else 0.0
    if window <= TUNED_WINDOW or untracked <= UNTRACKED_WARNING:
        return None
    return (f"warning: {untracked:.0%} of the detections are in no track at --window {window}: a window prices its frames "
            f"against its first frame's forecast, so long ones lose people; try --window {TUNED_WINDOW}")


def no_track_warning(detections: int, tracked: int) -> str | None:
    """A line when nothing was tracked: the result file is empty, which a wrong frame column
    (e.g. frames numbered in steps) makes silently, as births need boxes in consecutive frames."""
    if tracked or not detections:
        return None
    hits = Lifecycle().min_hits
    return (f"warning: none of the {detections} detections is in a track (an object is born from {hits} overlapping "
            f"boxes in consecutive frames); is column 1 the frame number, counted in steps of 1?")


def run_boxes(detections: Path, output: Path, formulation: str, seqinfo: Path | None, images: Path | None,
              window: int, as_json: bool, newcomer_test: bool = True, occluded: bool = True) -> None:
    """Read ``detections``, track them window by window, write ``output``, print the figures;
    ``newcomer_test``: ``Lifecycle.returns_compete``; ``occluded``: also write each object's
    boxes while it was held occluded between two sightings (``BoxTracks.with_occluded``)."""
    check_writable_output(output, detections, labeled=False)
    info = read_seqinfo(seqinfo) if seqinfo is not None else None
    boxes = read_detections(detections, info)
    if boxes.n_frames < 2:  # as `track`: nothing to follow from one frame
        raise InputError(f"{detections}: the sequence has 1 frame; tracking needs at least 2 (a template and one more)")
    solver = formulation_from_spec(formulation)
    histograms = None
    if images is not None:
        histograms = box_histograms(boxes, images, info.image_ext if info is not None else None)
    run = track_boxes(boxes, solver, window=window, histograms=histograms,
                      lifecycle=Lifecycle(returns_compete=newcomer_test))
    tracks = run.tracks.with_occluded() if occluded else run.tracks
    write_tracks(output, tracks)
    summary = {
        "frames": boxes.n_frames, "detections": len(boxes.frame), "tracked_boxes": len(run.tracks.frame),
        "occluded_boxes": int(tracks.occluded.sum()),
        "tracks": int(len(set(run.tracks.track_id.tolist()))), "formulation": formulation, "window": window,
        # None where no window proved a bound (nn-hungarian): 0 % would read as every window failing
        "integral_window_fraction": run.integral_windows / run.windows if run.bounded_windows else None,
        "seconds": round(run.seconds, 3), "frames_per_second": round(boxes.n_frames / max(run.seconds, 1e-9), 1),
        "histograms": histograms is not None, "newcomer_test": newcomer_test, "output": str(output),
    }
    if as_json:
        print(json.dumps(summary))
    else:
        out.print(" ".join(f"{key}={value}" for key, value in summary.items()), highlight=False)
    warn(normalised_warning(boxes))
    if boxes.image_size is not None and info is not None:
        warn(outside_image_warning(boxes, boxes.image_size, str(info.source)))
    elif images is not None:
        warn(outside_image_warning(boxes, frame_size(boxes, images, None), f"the frames in {images}"))
    warn(long_window_warning(window, len(boxes.frame), len(run.tracks.frame)))
    warn(no_track_warning(len(boxes.frame), len(run.tracks.frame)))
