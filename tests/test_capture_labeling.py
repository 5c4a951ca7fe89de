"""A labeling interrupted after any window resumes to exactly the uninterrupted result."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_fixtures import CMU, camera_capture, points_capture

from service.capture.capture import LabelingOptions
from service.capture.from_recording import capture_from_recording
from service.errors import InputError
from service.io.formats import read_labeled
from service.io.recording import Recording
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.loop import first_marker_state
from service.labeling.outcome import WindowOutcome


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize(
    ("make", "window"), [(lambda: points_capture(frames=120), 20), (lambda: camera_capture(frames=50), 10)],
    ids=["points", "cameras"],
)
def test_resume_after_a_stored_window_gives_the_uninterrupted_result(make, window):
    capture = make()
    options = LabelingOptions(window=window)
    uninterrupted = list(CaptureLabeling(capture, options).windows())
    expected = CaptureLabeling(capture, options).result(uninterrupted)
    assert len(uninterrupted) >= 5

    stored = [WindowOutcome.from_bytes(o.to_bytes()) for o in uninterrupted[:3]]  # then the process died
    restarted = CaptureLabeling(capture, options)
    outcomes = stored + list(restarted.windows(after=stored[-1]))
    result = restarted.result(outcomes)
    assert [o.index for o in outcomes] == list(range(len(uninterrupted)))
    assert _same(result.positions, expected.positions) and _same(result.filled, expected.filled)
    assert np.array_equal(result.point_index, expected.point_index)
    assert [o.stats.cost for o in outcomes] == [o.stats.cost for o in uninterrupted]


def test_resuming_needs_the_stored_marker_state():
    """Without the carried state (the first frame's instead) the rest of the labels change."""
    capture = points_capture(frames=120)
    labeling = CaptureLabeling(capture, LabelingOptions(window=20))
    uninterrupted = list(labeling.windows())
    first_state = first_marker_state(capture.names, capture.first_frame)
    stale = replace(uninterrupted[2], state=first_state)
    resumed = list(CaptureLabeling(capture, LabelingOptions(window=20)).windows(after=stale))
    assert any(not np.array_equal(a.point_index, b.point_index) for a, b in zip(resumed, uninterrupted[3:]))


def test_window_outcome_bytes_round_trip_exactly():
    outcome = next(CaptureLabeling(points_capture(frames=30)).windows())
    back = WindowOutcome.from_bytes(outcome.to_bytes())
    assert back.index == outcome.index and back.stats == outcome.stats
    assert _same(back.filled, outcome.filled) and np.array_equal(back.point_index, outcome.point_index)
    for name in outcome.state.__dataclass_fields__:
        assert _same(getattr(back.state, name), getattr(outcome.state, name)), name


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"formulation": "simplex-magic"}, "unknown formulation 'simplex-magic'"),
        ({"formulation": {"name": "ilp", "time_limit": -1}}, "time_limit"),
        ({"window": 1}, "window must be a whole number of at least 2"),
    ],
)
def test_bad_options_are_input_errors(fields, message):
    with pytest.raises(InputError, match=message):
        CaptureLabeling(points_capture(frames=5), LabelingOptions(**fields))


def test_a_library_user_gets_the_warnings_track_prints():
    """A take in cm read as mm is labeled (gates ten times too wide for it) and the library
    said nothing; ``warnings`` gives the lines `track` prints, here the body size's."""
    capture = points_capture(frames=30)
    scaled = replace(capture, first_frame=np.asarray(capture.first_frame) / 10,
                     points=[np.asarray(p) / 10 for p in capture.points])
    for take, expected in ((capture, False), (scaled, True)):
        labeling = CaptureLabeling(take, LabelingOptions(window=10, second_pass=False))
        labels, windows = labeling.label()
        lines = labeling.warnings(labels, windows)
        assert any("human-sized" in line for line in lines) is expected, lines


def test_a_time_limit_hit_is_among_the_warnings():
    """Deletions make the window LPs take longer than a microsecond (clean ones end in presolve)."""
    capture, rng = points_capture(frames=30), np.random.default_rng(0)
    gappy = [capture.points[0]] + [np.asarray(p)[rng.random(len(p)) > 0.1] for p in capture.points[1:]]
    labeling = CaptureLabeling(replace(capture, points=gappy),
                               LabelingOptions(formulation={"name": "lp-l1", "time_limit": 1e-6}, window=10))
    labels, windows = labeling.label()
    assert any("stopped at the solver's time limit" in line for line in labeling.warnings(labels, windows))


def test_a_camera_association_on_3d_points_is_refused():
    with pytest.raises(InputError, match="association 'per-camera' applies to camera captures"):
        CaptureLabeling(points_capture(frames=5), LabelingOptions(association="per-camera"))


def test_outcomes_of_another_labeling_are_refused():
    """Resumed with another window size, the stored state was used as the template of another
    frame and 9 labels came out wrong, silently; another capture's windows failed in numpy."""
    capture = points_capture(frames=60)
    stored = list(CaptureLabeling(capture, LabelingOptions(window=20, second_pass=False)).windows())
    other_size = CaptureLabeling(capture, LabelingOptions(window=10, second_pass=False))
    with pytest.raises(InputError, match="window 1 .frames 19-38. is not a window of this labeling"):
        other_size.windows(after=stored[1])
    with pytest.raises(InputError, match="not a window of this labeling"):
        other_size.result(stored)
    fewer = replace(capture, names=capture.names[:9], first_frame=np.asarray(capture.first_frame)[:9])
    with pytest.raises(InputError, match="holds the state of 41 markers; this capture labels 9"):
        CaptureLabeling(fewer, LabelingOptions(window=20, second_pass=False)).result(stored)
    same = CaptureLabeling(capture, LabelingOptions(window=20, second_pass=False))
    with pytest.raises(InputError, match="windows 0, 1, ... in order"):
        same.result(stored[1:])
    assert same.result(stored).n_frames == 60  # its own windows still assemble


def test_outcomes_of_another_take_of_the_same_markers_and_length_are_refused():
    """Same markers, same length, same window: every span and marker-count check passed, and the
    resumed windows were built on the other take's marker states, labels wrong without a word."""
    truth = read_labeled(CMU)
    options = LabelingOptions(window=20, second_pass=False)
    first, later = (capture_from_recording(Recording(truth.names, truth.positions[s:s + 60], truth.rate))
                    for s in (0, 60))
    stored = [WindowOutcome.from_bytes(o.to_bytes()) for o in CaptureLabeling(first, options).windows()]
    other = CaptureLabeling(later, options)
    with pytest.raises(InputError, match="window 1 was labeled from another capture"):
        other.windows(after=stored[1])
    with pytest.raises(InputError, match="window 0 was labeled from another capture"):
        other.result(stored)
    own = CaptureLabeling(first, options)
    assert all(o.labeling == own.fingerprint for o in stored)  # kept through bytes
    assert own.result(stored).n_frames == 60
    unstamped = [replace(o, labeling=None) for o in stored]  # stored before outcomes carried it
    assert other.result(unstamped).n_frames == 60


@pytest.mark.parametrize("scale", [1e-3, 1e3], ids=["metres-as-mm", "mm-as-metres"])
def test_a_take_in_the_wrong_unit_is_refused_before_labeling(scale):
    """A thousand times too big it came back 100 % occluded, with no error."""
    capture = points_capture(frames=5)
    scaled = replace(capture, first_frame=np.asarray(capture.first_frame) * scale,
                     points=[np.asarray(p) * scale for p in capture.points])
    with pytest.raises(InputError, match="the take's length unit is wrong"):
        CaptureLabeling(scaled)


def test_a_take_whose_markers_are_mostly_occluded_is_warned_of():
    """Cameras that saw nothing after frame 0: 99.3 % occluded, written with no warning line."""
    capture = camera_capture(frames=30)
    blind = replace(capture, detections=capture.detections[:1] + [[np.zeros((0, 2))] * len(capture.cameras)] * 29)
    for take, expected in ((capture, False), (blind, True)):
        labeling = CaptureLabeling(take, LabelingOptions(window=10))
        labels, windows = labeling.label()
        lines = labeling.warnings(labels, windows)
        assert any("of the marker-frames after the labeled frame are occluded" in line for line in lines) is expected, lines
