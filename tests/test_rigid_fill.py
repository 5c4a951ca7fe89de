"""A closed gap refilled by its donors' rigid motion from both sides (``formulations.markers.rigid_fill``)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import formulations.markers.rigid_fill as rigid_fill_module
from formulations.markers.gap_ends import tie_gap_ends
from formulations.markers.rigid_fill import rigid_fill, rigid_refill

FRAMES = 80
GAP = slice(30, 55)
BODY = np.array([[0, 0, 0], [80, 0, 0], [0, 90, 0], [0, 0, 100], [70, 60, 40]], float)


def _spinning_body(loose: bool = False, extra: np.ndarray | None = None) -> np.ndarray:
    """``(FRAMES, 5 or more, 3)``: a rigid body tumbling and translating, with ``extra`` markers
    on it; with ``loose``, one more marker swinging on its own 150 mm about its first marker."""
    angle = np.linspace(0.0, 10.0, FRAMES)
    spin = Rotation.from_rotvec(np.outer(angle, [0.3, 0.2, 0.93])).as_matrix()
    markers = BODY if extra is None else np.concatenate([BODY, extra])
    body = np.einsum("fij,kj->fki", spin, markers) + np.outer(np.arange(FRAMES) * 9.0, [1.0, 0.4, 0.0])[:, None]
    if not loose:
        return body
    swing = 150.0 * np.stack([np.sin(np.arange(FRAMES) / 4.0), np.cos(np.arange(FRAMES) / 3.0), np.zeros(FRAMES)], axis=1)
    return np.concatenate([body, (body[:, 0] + swing)[:, None]], axis=1)


def _hidden(truth: np.ndarray, marker: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Positions with ``marker`` unseen over ``GAP``, and the fill a blind carry gives there
    (its last sighting held), tied to both sightings as the labeler ties it."""
    positions = truth.copy()
    positions[GAP, marker] = np.nan
    filled = np.full_like(truth, np.nan)
    filled[GAP, marker] = truth[GAP.start - 1, marker]
    return positions, tie_gap_ends(positions, filled)


def test_a_tumbling_body_gives_the_hidden_marker_back_exactly():
    truth = _spinning_body()
    positions, tied = _hidden(truth)
    # What the tie to both sightings alone leaves: the body turned under the marker.
    assert np.linalg.norm(tied[GAP, 4] - truth[GAP, 4], axis=1).max() > 40.0
    refilled = rigid_fill(positions, tied)
    assert np.allclose(refilled[GAP, 4], truth[GAP, 4], atol=1e-6)
    assert np.isnan(refilled[~np.isnan(positions).any(axis=2)]).all()  # seen frames stay unfilled


def test_a_loose_donor_is_outweighed_by_the_rigid_ones():
    truth = _spinning_body(loose=True)
    positions, tied = _hidden(truth)
    positions[GAP, 1] = np.nan  # a rigid donor lost too: the swinging marker is among the four
    refilled = rigid_fill(positions, tied)
    # Its spread (about 100 mm) gives it a ten-thousandth of a rigid donor's weight.
    assert np.linalg.norm(refilled[GAP, 4] - truth[GAP, 4], axis=1).max() < 1.0


def test_frames_without_two_donors_on_both_sides_keep_their_fill():
    truth = _spinning_body()
    positions, tied = _hidden(truth)
    positions[GAP.stop : GAP.stop + 1, [1, 2, 3]] = np.nan  # three donors lost where the gap closes
    tied = tie_gap_ends(positions, np.where(np.isnan(positions), tied, np.nan))
    refilled = rigid_fill(positions, tied)
    # The closing side has one donor (0), and the others' one-frame gaps have one on either
    # side too: nothing is carried from it.
    assert np.array_equal(refilled[GAP, 4], tied[GAP, 4], equal_nan=True)


def test_a_gap_open_at_either_end_is_carried_from_its_one_sighting():
    truth = _spinning_body()
    positions = truth.copy()
    positions[:10, 4] = np.nan
    positions[70:, 2] = np.nan
    filled = np.where(np.isnan(positions), 7.0, np.nan)  # a fill that is nowhere near
    refilled, variance = rigid_refill(positions, filled)
    for frames, marker in ((slice(0, 10), 4), (slice(70, None), 2)):
        assert np.linalg.norm(refilled[frames, marker] - truth[frames, marker], axis=1).max() < 1e-6
        assert np.all(variance[frames, marker] < 2.0)  # rigid donors: their 1 mm^2 floor, combined


def test_a_gap_open_at_an_end_with_one_donor_keeps_its_fill():
    truth = _spinning_body()
    positions = truth.copy()
    positions[:10, 4] = np.nan
    positions[:10, 1:4] = np.nan  # one donor left in those frames
    filled = np.where(np.isnan(positions), 7.0, np.nan)
    refilled, variance = rigid_refill(positions, filled)
    assert np.all(refilled[:10, 4] == 7.0)
    assert np.all(np.isinf(variance[:10, 4]))


def _bar_and_a_far_marker() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Four markers on a bar (0.3 mm noise) and one 360 mm off it, all turning together and
    swaying sideways; the far one hidden over ``GAP``: truth, positions, and the tied blind fill."""
    bar = np.array([[0, 0, 0], [70, 0, 0], [140, 0, 0], [210, 0, 0], [105, 360, 0]], float)
    angle = np.linspace(0.0, 1.0, FRAMES)
    turn = Rotation.from_rotvec(np.outer(angle, [0.2, 0.3, 1.0])).as_matrix()
    truth = np.einsum("fij,kj->fki", turn, bar) + np.outer(100.0 * np.sin(np.arange(FRAMES) / 5.0), [0.0, 0.0, 1.0])[:, None]
    truth[:, :4] += np.random.default_rng(0).normal(0.0, 0.3, truth[:, :4].shape)
    positions, tied = _hidden(truth)
    return truth, positions, tied


def test_donors_on_one_line_carry_by_the_least_turn(monkeypatch: pytest.MonkeyPatch):
    truth, positions, tied = _bar_and_a_far_marker()
    # The tie to both sightings alone misses the sway.
    assert np.linalg.norm(tied[GAP, 4] - truth[GAP, 4], axis=1).max() > 50.0
    # The bar carries it along, its turn about the bar blended between the two sightings.
    assert np.linalg.norm(rigid_fill(positions, tied)[GAP, 4] - truth[GAP, 4], axis=1).max() < 5.0
    # A free fit would take the turn about the bar from the noise: the far marker goes astray.
    monkeypatch.setattr(rigid_fill_module, "MIN_SPAN_MM", 0.0)
    assert np.linalg.norm(rigid_fill(positions, tied)[GAP, 4] - truth[GAP, 4], axis=1).max() > 50.0


def test_a_lost_donor_refilled_counts_in_the_second_round(monkeypatch: pytest.MonkeyPatch):
    """Where marker 4's gap closes, three of its four donors are lost for a frame. Two more
    markers of the body, seen too briefly with marker 4 to be its donors (``MIN_SHARED_FRAMES``),
    are the lost ones' donors: round one refills those three, and round two carries 4 by them."""
    extra = np.array([[-60, 20, 30], [30, -70, 50]], float)
    truth = _spinning_body(extra=extra)
    positions, tied = _hidden(truth)
    positions[GAP.stop, [1, 2, 3]] = np.nan
    positions[: GAP.stop - 7, 5:] = positions[GAP.stop + 8 :, 5:] = np.nan
    tied = tie_gap_ends(positions, np.where(np.isnan(positions), truth[GAP.start - 1, 4], np.nan))
    assert np.allclose(rigid_fill(positions, tied)[GAP, 4], truth[GAP, 4], atol=1e-6)
    monkeypatch.setattr(rigid_fill_module, "ROUNDS", 1)
    assert np.linalg.norm(rigid_fill(positions, tied)[GAP, 4] - truth[GAP, 4], axis=1).max() > 20.0


def test_a_take_of_fewer_markers_than_donors_asked_is_filled():
    """Three markers: two donors at most, fewer than ``MAX_DONORS``, still carry the third."""
    truth = _spinning_body()[:, [0, 1, 4]]
    positions, tied = _hidden(truth, marker=2)
    refilled = rigid_fill(positions, tied)
    # Two donors lie on a line: the turn about it is blended from both sightings, not exact.
    assert np.linalg.norm(refilled[GAP, 2] - truth[GAP, 2], axis=1).max() < 40.0
    assert np.linalg.norm(tied[GAP, 2] - truth[GAP, 2], axis=1).max() > 40.0


def test_a_marker_labeled_in_too_few_frames_has_no_donors_and_no_warning():
    """A marker labeled in fewer frames than a spread needs has no donor at all (every spread
    inf): its combined variance is inf, quietly, and the others are filled as before."""
    truth = _spinning_body()
    positions, tied = _hidden(truth)
    positions[rigid_fill_module.MIN_SHARED_FRAMES - 1 :, 0] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        refilled, variance = rigid_refill(positions, tied)
    assert np.allclose(refilled[GAP, 4], truth[GAP, 4], atol=1e-6)
    assert np.isinf(variance[rigid_fill_module.MIN_SHARED_FRAMES - 1 :, 0]).all()
