"""A carried marker's carriers: the neighbours its rigid fit found moving with it (issue 11).

Issue 11's traced scene (``tests/test_drift.py``): a subject sits still, then the forearm
lifts; the radial wrist marker is lost from two frames into the lift and its ulnar mate for
the last four frames of that. Distances learned from sightings only hold the wrist as rigid
with the still thigh as with its forearm, so only the fit that carries it can tell them apart.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.markers.cloud_candidates import _shape_deviation
from formulations.markers.guide import GuideTrack, guide_track
from formulations.markers.state import MarkerState
from tests.test_drift import FOREARM, LOST, ULNAR, ULNAR_LOST, WRIST, _truth


def _carried_states() -> tuple[np.ndarray, list[MarkerState]]:
    """Truth and the state before each frame, the wrist and the ulnar hidden as in the scene."""
    truth = _truth()
    noisy = truth + np.random.default_rng(1).normal(0.0, 1.0, truth.shape)
    state, states = MarkerState.from_first_frame(noisy[0]), []
    for f in range(1, len(truth)):
        states.append(state)
        seen = np.ones(truth.shape[1], bool)
        seen[WRIST] = not LOST.start <= f < LOST.stop
        seen[ULNAR] = not ULNAR_LOST.start <= f < ULNAR_LOST.stop
        state = state.advance(noisy[f], seen)
    return truth, states


def test_the_still_thigh_is_learned_as_rigid_with_the_wrist_as_its_forearm_is():
    """The premise: before the lift nothing in the learned distances sets the forearm apart."""
    _, states = _carried_states()
    before = states[LOST.start - 2]
    on_forearm = before.neighbours[WRIST] < len(FOREARM)
    var = before.distance_var[WRIST]
    assert (~on_forearm).sum() >= 3
    assert np.median(var[~on_forearm]) < 2 * np.median(var[on_forearm])


def test_a_lost_wrist_is_carried_by_its_forearm_alone_and_stays_on_it_when_its_mate_is_lost():
    """Until the forearm has moved further than the fit's tolerance, everything moves with the
    wrist; after that only the forearm does, and it still does once the ulnar mate (one of
    the four carriers) is lost and the wrist re-anchors on the rest."""
    truth, states = _carried_states()
    moved = np.linalg.norm(truth[:, WRIST] - truth[0, WRIST], axis=1)
    for f in range(LOST.start + 1, LOST.stop):
        state = states[f - 1]  # the state before frame f
        carriers = state.neighbours[WRIST][state.carriers[WRIST]]
        assert len(carriers) >= 3, f
        if moved[f] > 30.0:
            assert (carriers < len(FOREARM)).all(), (f, carriers)
        assert np.linalg.norm(state.predict()[WRIST] - truth[f, WRIST]) < 12.0, f
    assert ULNAR in states[ULNAR_LOST.start - 1].neighbours[WRIST][states[ULNAR_LOST.start - 1].carriers[WRIST]]


def test_a_returning_wrist_is_judged_by_the_forearm_carrying_it_not_the_thigh():
    """At the wrist's return its own point fits the forearm; the still-learned thigh pairs,
    which the carry found apart, would make it look ~40 mm off its shape (and lend it to
    the ulnar marker, whose thigh pairs were learned loose while it was seen lifting)."""
    truth, states = _carried_states()
    f = LOST.stop
    state = states[f - 1]
    points = truth[f] + np.random.default_rng(2).normal(0.0, 1.0, truth[f].shape)
    guide = guide_track(state, [points])
    own = np.array([WRIST])

    def deviation(judged_by: GuideTrack) -> float:
        return float(_shape_deviation(state, judged_by, own, np.array([1]), points[own])[0])

    assert deviation(replace(guide, carriers=None)) > 20.0
    assert deviation(guide) < 5.0
