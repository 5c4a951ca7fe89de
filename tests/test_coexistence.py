"""Coexistence: a lost marker does not take a point whose track was seen beside it."""

import numpy as np
import pytest
from rigid_scenes import SwingingSegment

import service.labeling.cloud as cloud_chain
from formulations.markers.cloud_candidates import CloudGating, cloud_candidates
from formulations.markers.coexistence import BackLinks, coexisted
from formulations.markers.exchange import repair_exchanges
from formulations.markers.state import MarkerState
from formulations.markers.unnamed import WindowSurround
from service.io.recording import UnlabeledCloud

STEP = np.array([4.0, 1.0, 0.0])


def _walk(start: np.ndarray, frames: int) -> list[np.ndarray]:
    """Frames going back from the template: one point walking at STEP, a still one far off."""
    return [np.vstack([start - (k + 1) * STEP, [500.0, 0.0, 0.0]]) for k in range(frames)]


def back_tracks(points: np.ndarray, earlier: list[np.ndarray], reach: float, link_radius: float) -> np.ndarray:
    """The tracks of ``points`` (the template frame's) back through ``earlier``, the frame before the template first."""
    return BackLinks(earlier[::-1] + [points]).back_tracks(points, len(earlier), len(earlier), reach, link_radius)


def test_a_track_is_followed_back_at_its_own_velocity_until_it_ends():
    earlier = _walk(np.zeros(3), 6)
    earlier[4] = earlier[4][1:]  # the walking point is not there five frames back
    track = back_tracks(np.zeros((1, 3)), earlier, reach=10.0, link_radius=2.0)
    assert np.allclose(track[0, :4], [-(k + 1) * STEP for k in range(4)])
    assert np.isnan(track[0, 4:]).all()


def test_a_track_stops_where_two_points_could_continue_it():
    earlier = _walk(np.zeros(3), 4)
    earlier[2] = np.vstack([earlier[2], earlier[2][0] + [1.0, 0.0, 0.0]])  # a second point 1 mm off
    track = back_tracks(np.zeros((1, 3)), earlier, reach=10.0, link_radius=2.0)
    assert np.isfinite(track[0, :2]).all() and np.isnan(track[0, 2:]).all()


def test_links_kept_from_earlier_windows_give_the_tracks_measured_afresh():
    rng = np.random.default_rng(3)
    # points drifting apart at their own velocities, jittered, one missing now and then
    start, velocity = rng.uniform(0, 200, (6, 3)), rng.uniform(-3, 3, (6, 3))
    frames = [start + t * velocity + rng.normal(0, 0.2, (6, 3)) for t in range(80)]
    frames = [f[rng.random(6) > 0.02] for f in frames]
    kept = BackLinks(frames)
    for template, depth, link_radius in [(40, 30, 2.0), (45, 45, 1.5), (60, 50, 2.5), (79, 30, 2.0), (50, 50, 2.0)]:
        points = frames[template]
        again = kept.back_tracks(points, template, depth, 8.0, link_radius)
        afresh = BackLinks(frames).back_tracks(points, template, depth, 8.0, link_radius)
        assert np.isfinite(afresh[:, 5:]).any()  # the setup: tracks are followed some way back
        assert np.array_equal(again, afresh, equal_nan=True)


def test_only_a_track_seen_elsewhere_in_the_frame_a_marker_was_last_seen_coexisted():
    tracks = back_tracks(np.zeros((1, 3)), _walk(np.zeros(3), 5), reach=10.0, link_radius=2.0)
    own = -3 * STEP  # the track's own point three frames back
    seen_at = np.array([own, own + [80.0, 0.0, 0.0], own + [80.0, 0.0, 0.0], [np.nan] * 3, own])
    unseen = np.array([3, 3, 9, 3, 0])  # 9: the track does not reach back that far; 0: seen now
    assert coexisted(unseen, seen_at, tracks)[:, 0].tolist() == [False, True, False, False, False]


def _lost_state() -> tuple[MarkerState, np.ndarray]:
    """Four markers in a square, the fourth lost a frame ago; its own position comes back free."""
    square = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [100.0, 100.0, 0.0]])
    state = MarkerState.from_first_frame(square).advance(square, np.array([True, True, True, False]))
    return state, square[3:]


def test_the_exchange_repair_gives_a_lost_marker_a_fitting_point_unless_it_coexisted():
    state, free = _lost_state()
    repaired, moved = repair_exchanges(state, free)
    assert moved == 1 and repaired.visible[3]  # the setup: the shape alone hands it the point
    barred, moved = repair_exchanges(state, free, coexisting=np.array([[False], [False], [False], [True]]))
    assert moved == 0 and not barred.visible[3]


# A segment whose named markers lie in one plane: LOST and UNNAMED sit on either side of it,
# so each fits the other's distances to every named marker exactly.
PLANE = np.array([[0.0, 0, 0], [120.0, 0, 0], [0, 120.0, 0], [120.0, 120.0, 0], [60.0, 60.0, 60.0], [60.0, 60.0, -60.0]])
LOST, UNNAMED, HIDDEN, TEMPLATE = 4, 5, 30, 45
SWING = SwingingSegment(turn=(0.3, 0.2, 0.4), periods=(15, 20, 12), speed=6.0, sway=30.0, hinge=0, swing=0.8,
                        swing_period=6)


def _lost_marker_at_template() -> tuple[cloud_chain.CloudChain, MarkerState]:
    """The chain of a take where LOST is hidden from HIDDEN on and UNNAMED, which the labeled
    frame does not name, is seen throughout; and its state at TEMPLATE, labeled right so far."""
    truth = np.stack([SWING.frame(t, PLANE) for t in range(TEMPLATE + 2)])
    named = [i for i in range(truth.shape[1]) if i != UNNAMED]
    points = [truth[f, [i for i in range(truth.shape[1]) if f < HIDDEN or i != LOST]] for f in range(len(truth))]
    chain = cloud_chain.CloudChain(UnlabeledCloud(points, 100.0), [f"m{i}" for i in named], truth[0, named],
                                   unnamed_markers=1)
    state = MarkerState.from_first_frame(truth[0, named])
    seen = np.ones(len(named), bool)
    for f in range(1, TEMPLATE + 1):
        seen[named.index(LOST)] = f < HIDDEN
        state = state.advance(truth[f, named], seen)
    return chain, state


def test_a_lost_marker_is_not_handed_the_point_of_an_unnamed_marker_seen_beside_it(monkeypatch: pytest.MonkeyPatch):
    chain, state = _lost_marker_at_template()
    with monkeypatch.context() as without:  # the setup fails without the test: the shape hands it over
        without.setattr(cloud_chain, "coexisted", lambda unseen, seen_at, tracks: np.zeros((len(unseen), len(tracks)), bool))
        handed, _ = chain._exchanges_repaired(state, TEMPLATE, None)
        assert handed.visible[LOST]
    kept, apart = chain._exchanges_repaired(state, TEMPLATE, None)
    assert not kept.visible[LOST] and apart[LOST].sum() == 1  # UNNAMED's point, the one free point
    doubtful = np.ones(len(state.position))
    doubtful[LOST] = 0.5  # a doubtful marker's last point may not have been its own: no bar
    assert chain._exchanges_repaired(state, TEMPLATE, doubtful)[0].visible[LOST]


def _window_with_unnamed_track(coexisting: np.ndarray | None) -> np.ndarray:
    """Candidates of a window of five frames: three still markers, the third unseen for a
    frame, and a point no marker holds 20 mm from it and 10 mm from the second, there at the
    template and after."""
    named = np.array([[0.0, 0.0, 0.0], [20.0, 210.0, 0.0], [0.0, 200.0, 0.0]])
    state = MarkerState.from_first_frame(named)
    state = state.advance(named, np.ones(3, bool)).advance(named, np.array([True, True, False]))
    track = named[2] + [20.0, 0.0, 0.0]
    frames = [np.vstack([named, track]) for _ in range(5)]
    around = WindowSurround(frames[0], frames[0], frames[:2], known=1, coexisting=coexisting)
    window = cloud_candidates(state, frames, CloudGating(), None, around)
    return window.candidates.object[window.point == 3]


def test_a_window_offers_a_seeded_unnamed_track_to_no_marker_seen_apart_from_it():
    takers = _window_with_unnamed_track(None)
    assert 2 in takers  # the setup: the unseen marker may take the track
    assert 1 not in takers  # seen at the template beside it
    apart = np.zeros((3, 4), bool)
    apart[2, 3] = True  # the third marker was last seen apart from the track of template point 3
    takers = _window_with_unnamed_track(apart)
    assert 2 not in takers
