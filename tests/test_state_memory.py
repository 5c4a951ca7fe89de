"""Labeling holds a bounded number of marker states, not one per frame of the take.

Each ``MarkerState`` remembers the states it was advanced to, so an advance made twice is
computed once; kept in a plain dict, that chained every frame's state to the next and the
take's first state held them all (40 KB a frame at 41 markers: 5.5 GB over 50,000 frames)."""

from __future__ import annotations

import gc

from service_fixtures import generated_capture

from formulations.markers.state import MarkerState
from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling


def _live_states() -> int:
    gc.collect()
    return sum(isinstance(thing, MarkerState) for thing in gc.get_objects())


def test_states_of_labeled_frames_are_let_go() -> None:
    before = _live_states()
    labeling = CaptureLabeling(generated_capture(frames=300, seed=1), LabelingOptions(window=20))
    outcomes = list(labeling.windows())
    held = _live_states() - before
    assert len(outcomes) > 10
    assert held < 100, f"{held} marker states held after {labeling.n_windows} windows of a 300-frame take"
