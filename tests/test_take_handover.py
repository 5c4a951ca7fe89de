"""A track handed over to a long-lost marker, given back to the marker it continues: the traced
OpenSim walking5 case (the left lateral condyle, lost for 140 frames, took the thigh marker's
points while the thigh marker was read as occluded), on a rigid segment in motion."""

import json
from pathlib import Path

import numpy as np
import pytest
from rigid_scenes import SwingingSegment
from service_fixtures import document_json, generated_capture
from typer.testing import CliRunner

import service.labeling.exchanged as exchanged_module
from formulations.markers.state import MarkerState
from formulations.markers.take_handover import FirstShape, Handover, _Headings, hand_back, step_sd, take_handovers
from service.cli.app import app
from service.io.recording import LabeledTrajectories
from service.labeling.exchanged import EXCHANGED_CONFIDENCE, handed_back

# A thigh-like plate: the owner (3) and, 7 mm from it, a close neighbour (5); the taker (4)
# sits 150 mm from the owner.
SEGMENT = np.array([[0, 0, 0], [80, 10, 0], [40, -60, 10], [160, 20, -10], [20, 110, 30], [165, 25, -8]], float)
OWNER, TAKER, CLOSE = 3, 4, 5
WALK = SwingingSegment(turn=(0.3, 0.2, 0.4), periods=(19, 23, 17), speed=4.0, sway=30.0, hinge=0, swing=0.6, swing_period=9)
FRAMES, LOST_AT, HANDED_AT = 360, 40, 300


def _take(seed: int, noise: float = 1.5) -> np.ndarray:
    """``(FRAMES, 8, 3)``: the plate, a swinging marker and a far one, with noise."""
    rng = np.random.default_rng(seed)
    return np.stack([WALK.frame(t, SEGMENT) for t in range(FRAMES)]) + rng.normal(0, noise, (FRAMES, 8, 3))


def _lost(take: np.ndarray, marker: int, drift_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Labels with ``marker`` unseen from ``LOST_AT`` on, and a fill that drifts ``drift_mm``."""
    labels, fill = take.copy(), np.full_like(take, np.nan)
    labels[LOST_AT:, marker] = np.nan
    ramp = np.linspace(0.0, drift_mm, FRAMES - LOST_AT)[:, None] * np.array([0.6, 0.8, 0.0])
    fill[LOST_AT:, marker] = take[LOST_AT:, marker] + ramp
    return labels, fill


def _both_lost(take: np.ndarray, lost_at: dict[int, int], until: int) -> tuple[np.ndarray, np.ndarray]:
    """Labels with each marker of ``lost_at`` unseen from its frame to ``until``, and a fill
    that drifts 60 mm over that stretch."""
    labels, fill = take.copy(), np.full_like(take, np.nan)
    for marker, start in lost_at.items():
        labels[start:until, marker] = np.nan
        fill[start:until, marker] = take[start:until, marker] + np.linspace(0.0, 60.0, until - start)[:, None]
    return labels, fill


def _handovers(labels: np.ndarray, fill: np.ndarray) -> list[tuple[int, int, int, int]]:
    neighbours = MarkerState.from_first_frame(labels[0], n_neighbours=5).neighbours
    return [(h.owner, h.taker, h.start, h.stop) for h in take_handovers(labels, labels[0], neighbours, fill)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_track_taken_by_a_long_lost_marker_is_given_back(seed: int) -> None:
    take = _take(seed)
    labels, fill = _lost(take, TAKER, drift_mm=150.0)
    labels[HANDED_AT:, TAKER], labels[HANDED_AT:, OWNER] = take[HANDED_AT:, OWNER], np.nan
    fill[HANDED_AT:, OWNER] = take[HANDED_AT:, OWNER] + 5.0
    assert _handovers(labels, fill) == [(OWNER, TAKER, HANDED_AT, FRAMES)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_marker_that_really_comes_back_as_another_leaves_keeps_its_points(seed: int) -> None:
    """The owner is occluded from 300 and the close neighbour, lost since 40, returns at 300 on
    its own point, 7 mm from where the owner was heading and 40 mm from its own drifted fill:
    the kinematics alone would hand it over; its first-frame distances to the plate say no."""
    take = _take(seed)
    labels, fill = _lost(take, CLOSE, drift_mm=40.0)
    labels[HANDED_AT:, CLOSE], labels[HANDED_AT:, OWNER] = take[HANDED_AT:, CLOSE], np.nan
    fill[HANDED_AT:, CLOSE] = np.nan
    fill[HANDED_AT:, OWNER] = take[HANDED_AT:, OWNER]
    assert _handovers(labels, fill) == []


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_right_labels_are_left_alone(seed: int) -> None:
    take = _take(seed)
    labels, fill = _lost(take, TAKER, drift_mm=150.0)
    labels[HANDED_AT:, TAKER] = take[HANDED_AT:, TAKER]  # it really comes back, far from the owner
    labels[HANDED_AT:, OWNER] = np.nan
    fill[HANDED_AT:, TAKER], fill[HANDED_AT:, OWNER] = np.nan, take[HANDED_AT:, OWNER]
    assert _handovers(take, np.full_like(take, np.nan)) == []
    assert _handovers(labels, fill) == []


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_returning_marker_taken_by_a_lost_neighbour_is_given_back_on_the_first_frames_say(seed: int) -> None:
    """Both lost (the taker from 150, the owner from 200), the owner's point back at 300 but
    held by the taker for 10 frames: no heading is sure (the owner's prediction drifted 80 mm),
    the plate's distances say whose point it is."""
    take = _take(seed)
    labels, fill = take.copy(), np.full_like(take, np.nan)
    for marker, lost_at, drift in ((TAKER, 150, [0.0, 90.0, 0.0]), (OWNER, 200, [0.0, 50.0, 60.0])):
        labels[lost_at:, marker] = np.nan
        fill[lost_at:, marker] = take[lost_at:, marker] + np.linspace(0.0, 1.0, FRAMES - lost_at)[:, None] * drift
    back = slice(HANDED_AT, HANDED_AT + 10)
    labels[back, TAKER], fill[back, TAKER] = take[back, OWNER], np.nan
    assert _handovers(labels, fill) == [(OWNER, TAKER, HANDED_AT, HANDED_AT + 10)]
    labels[back, TAKER] = take[back, TAKER]  # it really was the taker coming back
    assert _handovers(labels, fill) == []


@pytest.mark.parametrize("sigma", [0.5, 2.0, 4.0])
def test_the_step_sd_is_that_of_the_constant_velocity_residual(sigma: float) -> None:
    """x_t - 2 x_(t-1) + x_(t-2) of a constant-velocity track has sd sqrt(6) sigma per axis."""
    rng = np.random.default_rng(7)
    track = np.arange(2000)[:, None, None] * np.array([3.0, -1.0, 0.5]) + rng.normal(0, sigma, (2000, 1, 3))
    assert step_sd(track)[0] == pytest.approx(np.sqrt(6) * sigma, rel=0.1)


def test_every_per_label_array_follows_the_hand_over() -> None:
    take = _take(0)
    positions, fill = _lost(take, TAKER, drift_mm=150.0)
    positions[HANDED_AT:, TAKER], positions[HANDED_AT:, OWNER] = take[HANDED_AT:, OWNER], np.nan
    fill[HANDED_AT:, OWNER] = take[HANDED_AT:, OWNER]
    occluded = ~np.isfinite(positions).all(axis=2)
    point_index = np.where(occluded, -1, np.arange(8)[None])
    point_index[HANDED_AT:, TAKER] = OWNER
    labels = LabeledTrajectories(
        names=[f"m{k}" for k in range(8)], positions=positions, occluded=occluded, rate=100.0,
        point_index=point_index, filled=fill, confidence=np.full((FRAMES, 8), 0.9),
    )
    back, handovers = handed_back(labels, MarkerState.from_first_frame(take[0], n_neighbours=5))
    assert handovers == [Handover(OWNER, TAKER, HANDED_AT, FRAMES)]
    run = slice(HANDED_AT, FRAMES)
    assert np.array_equal(back.positions[run, OWNER], take[run, OWNER])
    assert (back.point_index[run, OWNER] == OWNER).all() and (back.point_index[run, TAKER] == -1).all()
    assert back.occluded[run, TAKER].all() and not back.occluded[run, OWNER].any()
    assert np.isnan(back.filled[run, OWNER]).all()
    assert np.array_equal(back.filled[run, TAKER], np.repeat(fill[[HANDED_AT - 1], TAKER], FRAMES - HANDED_AT, axis=0))
    assert (back.confidence[run, OWNER] == EXCHANGED_CONFIDENCE).all()
    assert np.array_equal(back.positions[:HANDED_AT], positions[:HANDED_AT], equal_nan=True)


def test_track_says_which_tracks_it_handed_back(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The summary reports the hand-overs undone (one is forced on a generated take, so that the
    report, not the repair, is what is checked)."""
    source, capture = tmp_path / "take.json", generated_capture(60)
    source.write_text(document_json(capture))
    monkeypatch.setattr(exchanged_module, "take_handovers", lambda *args: [Handover(1, 0, 20, 40)])
    done = CliRunner().invoke(app, ["track", str(source), "--out", str(tmp_path / "a.csv"), "--json", "--one-pass"])
    assert done.exit_code == 0, done.output
    summary = json.loads(done.stdout.splitlines()[-1])
    assert summary["handed_back"] == [{"owner": capture.names[1], "taker": capture.names[0], "frames": [20, 40]}]
    line = CliRunner().invoke(app, ["track", str(source), "--out", str(tmp_path / "b.csv"), "--one-pass"], env={"COLUMNS": "400"})
    assert "1 track handed back to the marker it continues (labels doubtful)" in line.stdout


def test_headings_updated_for_the_two_markers_a_hand_over_moves_equal_fresh_ones() -> None:
    """The scan keeps each marker's headings and recomputes only the owner's and taker's after
    a hand-over: they must equal headings computed afresh from the edited labels and fill."""
    rng = np.random.default_rng(3)
    labels = np.cumsum(rng.normal(0, 2, (120, 6, 3)), axis=0)
    labels[rng.random((120, 6)) < 0.3] = np.nan
    fill = np.where(np.isnan(labels), labels[0] + rng.normal(0, 5, labels.shape), np.nan)
    headings = _Headings(labels, fill, range(6))
    handover = Handover(owner=1, taker=4, start=50, stop=90)
    hand_back(labels, fill, handover)
    headings.update(labels, fill, (handover.owner, handover.taker))
    fresh = _Headings(labels, fill, range(6))
    np.testing.assert_array_equal(headings.owner, fresh.owner)
    np.testing.assert_array_equal(headings.taker, fresh.taker)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_claim_the_windows_undo_once_both_are_seen_is_not_made(seed: int) -> None:
    """Both lost, the taker back on its own point at 300, and the one plate marker seen beside
    it moved as a joint moves it, so that the first frame's shape says the point is the owner's
    (CMU 85_02 under the hard preset: RTOE's points claimed for RMT5 on the ankle marker alone).
    At 310 the owner is seen again on its own point and the taker goes on along its track: the
    windows, seeing both, read the track as the taker's, and it stays so. Where the taker is
    lost again at 310, nothing says the track is its own, and the claim stands."""
    take = _take(seed)
    labels, fill = _both_lost(take, {TAKER: 150, OWNER: 200}, FRAMES)
    back, witness = slice(HANDED_AT, HANDED_AT + 10), 1
    labels[HANDED_AT:, TAKER] = take[HANDED_AT:, TAKER]
    labels[back, 0], labels[back, 2], labels[back, CLOSE] = np.nan, np.nan, np.nan  # the rest of the plate unseen
    away = labels[back, witness] - labels[back, TAKER]
    owner_distance = np.linalg.norm(take[0, OWNER] - take[0, witness])
    labels[back, witness] = labels[back, TAKER] + away / np.linalg.norm(away, axis=1, keepdims=True) * owner_distance
    labels[HANDED_AT + 10 :, OWNER] = take[HANDED_AT + 10 :, OWNER]
    assert _handovers(labels, fill) == []
    labels[HANDED_AT + 10 :, TAKER] = np.nan  # the taker lost again: nothing says the track is its own
    assert _handovers(labels, fill) == [(OWNER, TAKER, HANDED_AT, HANDED_AT + 10)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_claim_stands_when_the_windows_then_hold_the_pair_exchanged(seed: int) -> None:
    """Both lost, the taker back at 300 on the owner's point and on along its track after the
    owner is seen again at 310, on the taker's own point: the windows hold the pair exchanged
    (the tennis serve's left wrist markers with ghosts). The plate's distances say so over those
    frames too, so the claim is made."""
    take = _take(seed)
    labels, fill = _both_lost(take, {TAKER: 250, OWNER: 270}, HANDED_AT)
    labels[HANDED_AT:HANDED_AT + 10, OWNER] = np.nan
    exchanged = slice(HANDED_AT + 10, HANDED_AT + 20)  # then each back on its own track
    labels[HANDED_AT : exchanged.stop, TAKER] = take[HANDED_AT : exchanged.stop, OWNER]
    labels[exchanged, OWNER] = take[exchanged, TAKER]
    assert _handovers(labels, fill)[:1] == [(OWNER, TAKER, HANDED_AT, HANDED_AT + 10)]


@pytest.mark.parametrize("kept_elsewhere", [False, True])
def test_a_claim_needs_owner_witnesses_that_keep_the_first_frame_where_it_is_labeled(kept_elsewhere: bool) -> None:
    """The basket sprint's ear, "rigid" with a forearm and an elbow that were still while it
    was labeled, not as in the first frame. The taker (1) is back at 50 on a point 160 mm from
    its witness (3) against 100 in its first frame and elsewhere; the owner's witness (2) sits
    there 50 mm from the point, as from the owner in the first frame. Where the owner's own
    labels keep that 50 mm, the witness judges and the claim stands; where they sit 90 mm from
    it, the witness fits the owner nowhere, says nothing here, and the claim is not made."""
    frames, run = 100, slice(50, 60)
    positions = np.full((frames, 4, 3), np.nan)
    positions[:, 2], positions[:, 3] = [160.0, 50.0, 0.0], [0.0, 0.0, 0.0]
    positions[:50, 0] = [210.0, 50.0, 0.0] if kept_elsewhere else [250.0, 50.0, 0.0]  # the owner, lost at 50
    positions[0, 0] = [210.0, 50.0, 0.0]
    positions[:, 1], positions[run, 1] = [100.0, 0.0, 0.0], [160.0, 0.0, 0.0]
    positions += np.random.default_rng(0).normal(0.0, 0.5, positions.shape)
    spread = np.full((4, 4), np.inf)
    spread[0, 2] = spread[2, 0] = spread[1, 3] = spread[3, 1] = 25.0
    shape = FirstShape(spread, spread < 100.0, np.linalg.norm(positions[0][:, None] - positions[0][None], axis=2))
    assert shape.claims(positions, 0, 1, run.start, run.stop) == kept_elsewhere
