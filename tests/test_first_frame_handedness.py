"""Handedness in the merges (``formulations.markers.first_frame_handedness``): an exchange of two
markers that are mirror images across their mates' plane keeps every distance, so the bends
cannot see it; the signed volume of the rigid quadruple can."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.markers.first_frame_handedness import KEPT_SHARE, MIRRORED_SHARE, first_frame_judges, mirrored_side
from formulations.markers.pass_merge import labels_taken
from formulations.markers.state import MarkerState

FRAMES = 80
TOE, FIFTH = 2, 3  # mirror images across the heel-ankle plane: exchanged, every distance fits


def _foot(seed: int = 0, noise_mm: float = 0.5) -> np.ndarray:
    """``(F, 4, 3)`` heel, ankle, toe and fifth metatarsal, the toe and fifth mirror images
    through the plane of heel and ankle, turning and walking rigidly, with a little noise."""
    body = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 60.0], [140.0, 30.0, 0.0], [140.0, -30.0, 0.0]])
    rng = np.random.default_rng(seed)
    frames = []
    for f in range(FRAMES):
        angle = 0.03 * f
        turn = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0.0, 0.0, 1.0]])
        frames.append(body @ turn.T + [5.0 * f, 0.0, 100.0])
    return np.stack(frames) + rng.normal(0.0, noise_mm, (FRAMES, 4, 3))


def _exchanged(truth: np.ndarray, after: int) -> tuple[np.ndarray, np.ndarray]:
    """Point indices (point i of each frame is marker i's) and positions, toe and fifth exchanged from ``after``."""
    points = np.tile(np.arange(4), (FRAMES, 1))
    points[after:, [TOE, FIFTH]] = points[after:, [FIFTH, TOE]]
    return points, truth[np.arange(FRAMES)[:, None], points]


def _neighbours(truth: np.ndarray) -> np.ndarray:
    return MarkerState.from_first_frame(truth[0], n_neighbours=3).neighbours


def test_an_exchange_of_mirror_images_flips_the_handedness_of_both() -> None:
    truth = _foot()
    wrong = _exchanged(truth, 30)[1]
    flips = first_frame_judges([truth, wrong], truth[0], _neighbours(truth)).flips
    assert np.nansum(flips[0]) == 0 and np.isfinite(flips[0]).mean() > 0.9  # a rigid motion keeps it, judged nearly everywhere
    assert np.all(flips[1][30:, [TOE, FIFTH]] == 1) and np.all(flips[1][:30] == 0)


def test_a_flat_quadruple_is_not_judged() -> None:
    truth = _foot(noise_mm=0.0)
    truth[:, 1] = 0.5 * (truth[:, 0] + truth[:, 2])  # the ankle between heel and toe: no handedness
    assert np.isnan(first_frame_judges([truth], truth[0], _neighbours(truth)).flips).all()


@pytest.mark.parametrize("shares, side", [
    ((MIRRORED_SHARE, KEPT_SHARE), 0), ((KEPT_SHARE, MIRRORED_SHARE), 1),
    ((MIRRORED_SHARE - 0.05, 0.0), None), ((1.0, KEPT_SHARE + 0.05), None),
])
def test_mirrored_side_needs_most_of_one_and_almost_none_of_the_other(shares: tuple[float, float], side: int | None) -> None:
    flips = np.array([[1.0] * round(100 * s) + [0.0] * (100 - round(100 * s)) for s in shares])
    assert mirrored_side(flips) == side


def test_too_few_judged_labels_decide_nothing() -> None:
    assert mirrored_side(np.array([[1.0, 1.0, np.nan], [0.0, 0.0, 0.0]])) is None


def test_the_merge_takes_the_unmirrored_labels_where_the_bends_cannot_tell() -> None:
    """The exchange keeps every distance, so judged by bends alone the two passes tie and the
    merge keeps the first, here the exchanged one; with the handedness it takes the right one."""
    truth = _foot(noise_mm=0.0)
    right, wrong = (np.tile(np.arange(4), (FRAMES, 1)), truth), _exchanged(truth, 30)
    positions = [wrong[1], right[1]]  # the exchanged pass first: the one kept unless the merge takes the other
    judges = first_frame_judges(positions, truth[0], _neighbours(truth))
    assert not labels_taken((wrong[0], right[0]), judges.capped, judges.judged).any()  # bends alone: the exchange stays
    take = labels_taken((wrong[0], right[0]), judges.capped, judges.judged, flips=judges.flips)
    assert np.array_equal(np.where(take, right[0], wrong[0]), right[0])
