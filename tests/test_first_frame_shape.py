"""Judging labelings of one take by their rigid pairs against the labeled first frame."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from formulations.markers.first_frame_shape import CAP_MM, first_frame_disagreement, pair_offsets, rigid_mates
from formulations.markers.state import MarkerState
from formulations.markers.take_spread import take_spread


def _two_segments(frames: int = 200, seed: int = 0) -> np.ndarray:
    """``(F, 8, 3)``: a foot-like plate of four markers and a shank of four, 1 mm noise; the
    shank turns about the plate's first marker, so only pairs within a segment are rigid."""
    rng = np.random.default_rng(seed)
    foot = np.array([[0, 0, 0], [80, 0, 0], [180, 30, 0], [150, -40, 10]], float)
    shank = np.array([[0, 0, 120], [30, 20, 250], [-20, 30, 330], [10, -30, 400]], float)
    positions = np.empty((frames, 8, 3))
    for t in range(frames):
        body = Rotation.from_rotvec([0, 0, 0.01 * t])
        knee = Rotation.from_rotvec([0.6 * np.sin(t / 15), 0, 0])
        positions[t, :4] = body.apply(foot) + [2.0 * t, 0, 0]
        positions[t, 4:] = body.apply(knee.apply(shank)) + [2.0 * t, 0, 0]
    return positions + rng.normal(0, 1.0, positions.shape)


def _neighbours(first: np.ndarray) -> np.ndarray:
    return MarkerState.from_first_frame(first, n_neighbours=7).neighbours


def _cycled(positions: np.ndarray, markers: list[int], start: int) -> np.ndarray:
    """The labeling with ``markers`` passed round (each holds the next one's point) from ``start``."""
    wrong = positions.copy()
    wrong[start:, markers] = positions[start:, np.roll(markers, -1)]
    return wrong


def test_a_labeling_that_passes_a_plate_round_is_judged_worse_than_the_right_one() -> None:
    right = _two_segments()
    first = right[0]
    wrong = _cycled(right, [0, 1, 2, 3], start=40)  # wrong over 80 % of the take
    off = first_frame_disagreement([wrong, right], first, _neighbours(first))
    assert off[1] < 3.0 and off[0] > 4 * off[1]  # half the markers wrong over 80 % of the frames


def test_the_pairs_judged_are_the_rigid_ones_in_either_labeling() -> None:
    """Judged by its own spreads alone, the wrong labeling's plate looks loose (its distances
    change at the exchange) and the right one's partners differ; the rigidity both share is
    the least spread either shows, so the plate's pairs judge both."""
    right = _two_segments(seed=1)
    first, neighbours = right[0], _neighbours(right[0])
    wrong = _cycled(right, [0, 1, 2, 3], start=40)
    own_spread = take_spread(wrong, neighbours)
    plate = np.isin(neighbours[:4], [0, 1, 2, 3])
    assert np.median(own_spread[:4][plate]) > 100.0  # the wrong pass alone would not call the plate rigid
    alone = first_frame_disagreement([wrong], first, neighbours)
    both = first_frame_disagreement([wrong, right], first, neighbours)
    assert both[0] > alone[0]


def test_the_disagreement_is_the_capped_mean_over_partner_pairs_either_labeling_labels() -> None:
    """Against a loop over frames, markers and partners on random labelings with gaps; a pair
    one labeling leaves out where the other labels it costs it the cap."""
    rng = np.random.default_rng(3)
    labelings = [_two_segments(60, seed=s) + rng.normal(0, 8.0, (60, 8, 3)) for s in (4, 5)]
    for labeling in labelings:
        labeling[rng.random((60, 8)) < 0.2] = np.nan
    first = _two_segments(1, seed=6)[0]
    neighbours = _neighbours(first)
    got = first_frame_disagreement(labelings, first, neighbours, partners=2, cap_mm=12.0)
    spread = np.fmin(*(take_spread(labeling, neighbours) for labeling in labelings))
    terms: list[list[float]] = [[], []]
    for m in range(8):
        for k in np.argsort(np.where(np.isfinite(spread[m]), spread[m], np.inf))[:2]:
            j = neighbours[m, k]
            rest = np.linalg.norm(first[m] - first[j])
            for t in range(60):
                together = [np.isfinite(lab[t, [m, j]]).all() for lab in labelings]
                if not any(together):
                    continue
                for p, labeling in enumerate(labelings):
                    off = abs(np.linalg.norm(labeling[t, m] - labeling[t, j]) - rest) if together[p] else 12.0
                    terms[p].append(min(off, 12.0))
    assert np.allclose(got, [np.mean(terms[0]), np.mean(terms[1])])


def test_a_labeling_that_leaves_right_labels_out_is_judged_worse() -> None:
    """Judged only on what it labels, a labeling would win by labeling less."""
    right = _two_segments(seed=2)
    sparse = right.copy()
    sparse[::2, 1] = np.nan  # marker 1 left out in every other frame
    off = first_frame_disagreement([sparse, right], right[0], _neighbours(right[0]))
    assert off[1] < off[0]


def test_nothing_labeled_together_is_nan_and_a_labeling_without_pairs_pays_the_cap() -> None:
    right = _two_segments(30)
    lonely = np.full_like(right, np.nan)
    lonely[:, 0] = right[:, 0]
    neighbours = _neighbours(right[0])
    off = first_frame_disagreement([lonely, right], right[0], neighbours)
    assert off[0] == 50.0 and off[1] < 5.0
    assert np.isnan(first_frame_disagreement([lonely, lonely], right[0], neighbours)).all()


def test_a_label_on_a_close_neighbours_point_costs_the_cap_though_it_bends_its_pairs_less() -> None:
    """Marker 0 put on marker 1's point, 30 mm away, bends its pairs to markers 2 and 4 (60 and
    57 mm off the other side) by 30 and 24 mm: under the 50 mm cap, so it cost less than
    leaving 0 out did. Past the tolerance (half its nearest-neighbour distance, as 5 spreads of
    pairs this rigid are less) they cost the cap; the pairs it bends by less keep their offsets."""
    rng = np.random.default_rng(7)
    cloud = np.array([[0, 0, 0], [30, 0, 0], [-60, 0, 0], [0, 0, 60], [-40, 40, 0], [0, 400, 400]], float)
    right = cloud + rng.normal(0, 0.3, (60, 6, 3))
    wrong = right.copy()
    wrong[20:, 0], wrong[20:, 1] = right[20:, 1], np.nan
    neighbours = MarkerState.from_first_frame(right[0], n_neighbours=5).neighbours
    capped, _ = pair_offsets([right, wrong], right[0], neighbours, partners=5)
    rest = np.linalg.norm(right[0, 0] - right[0, 2:], axis=1)
    bent = np.abs(np.linalg.norm(right[30, 1] - right[30, 2:], axis=1) - rest)  # markers 2 .. 5 from 1's point
    assert bent[[0, 2]].min() > 20.0 and bent[[0, 2]].max() < CAP_MM and bent[[1, 3]].max() < 10.0
    wrong_row = np.sort(capped[1, 30, 0])
    assert wrong_row[-3:].tolist() == [CAP_MM] * 3  # the pairs to 2 and 4, and to 1, which it left out
    assert np.allclose(wrong_row[:2], np.sort(bent[[1, 3]]))
    assert capped[0, 30, 0].max() < 3.0


def test_a_labeling_that_labels_a_marker_only_while_still_does_not_make_it_rigid_with_another_segment() -> None:
    """The leg stands still for 25 frames, then the shank swings about foot marker 0. One
    labeling labels shank marker 4 only in the still frames, where its pairs to foot markers
    1-3 vary by noise alone; the other labels it everywhere. The least spread either shows
    would make the foot its rigid mates; a spread over a tenth of the frames the other
    labeling shows the pair in is not heard, so its mates are the shank's and the pivot."""
    right = _two_segments(frames=250, seed=2)
    right[:25] = right[0] + np.random.default_rng(3).normal(0, 1.0, (25, 8, 3))  # still: the first frame's pose
    sparse = right.copy()
    sparse[25:, 4] = np.nan
    neighbours = _neighbours(right[0])
    foot = np.isin(neighbours[4], [1, 2, 3])
    still, moving = take_spread(sparse, neighbours)[4], take_spread(right, neighbours)[4]
    assert np.sort(still[foot])[:2].max() < np.sort(moving[~foot])[2]  # the least spread alone picks foot mates
    assert not np.isin(rigid_mates([sparse, right], neighbours, partners=3)[0][4], [1, 2, 3]).any()
    assert np.isin(rigid_mates([sparse], neighbours, partners=3)[0][4], [1, 2, 3]).sum() >= 2  # alone, it is all there is
