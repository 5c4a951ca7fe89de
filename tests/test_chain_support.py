"""A reading is credited with the jointed pair it lets ``joint_place`` pose (``chain_support``).

The setup: an equilateral three-marker segment fits its points equally well in all six
orders, so its own markers cannot tell the readings apart; a two-marker segment hangs from
a joint beyond one corner, and only the true reading puts that joint where the pair is.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import cdist
from scipy.spatial.transform import Rotation

from formulations.subject.chain_support import chain_support
from formulations.subject.constellation import Hypothesis, segment_hypotheses
from formulations.subject.geometry import JointGeometry, ModelGeometry, SegmentGeometry
from formulations.subject.identify import identify
from formulations.subject.tree_choice import choose_hypotheses

SIDE = 120.0  # mm
TRIANGLE = SIDE / np.sqrt(3) * np.array([[np.cos(a), np.sin(a), 0.0] for a in (0.5 * np.pi, 7 / 6 * np.pi, 11 / 6 * np.pi)])
CENTRE_A = np.array([0.0, 150.0, 20.0])  # beyond the first corner, out of the plane
PAIR = np.array([[0.0, 0.0, -90.0], [0.0, 60.0, -170.0]])  # the pair in its own frame, centre at the origin


def _geometry() -> ModelGeometry:
    tau = np.full(3, 6.0)
    segments = [
        SegmentGeometry("plate", np.arange(3), TRIANGLE, np.ones(3), tau),
        SegmentGeometry("rod", np.arange(3, 5), PAIR - PAIR.mean(axis=0), np.ones(2), tau[:2]),
    ]
    joint = JointGeometry(0, 1, CENTRE_A, -PAIR.mean(axis=0), 10.0, 2.0)
    segment_of = np.array([0, 0, 0, 1, 1])
    return ModelGeometry(["p0", "p1", "p2", "r0", "r1"], segments, [joint], [], segment_of, 5.0, 3.0)


def _frame(seed: int) -> np.ndarray:
    """The five markers in a random pose (the rod turned about the joint), in marker order."""
    rng = np.random.default_rng(seed)
    turn, bend = Rotation.random(random_state=rng).as_matrix(), Rotation.random(random_state=rng).as_matrix()
    origin = rng.normal(0, 500, 3)
    plate = TRIANGLE @ turn.T + origin
    centre = turn @ CENTRE_A + origin
    rod = PAIR @ (turn @ bend).T + centre
    return np.concatenate([plate, rod])


def _plate_choice(geometry: ModelGeometry, points: np.ndarray, support: bool) -> np.ndarray:
    distance = cdist(points, points)
    by_segment = [segment_hypotheses(s, segment, points, distance) for s, segment in enumerate(geometry.segments)]
    extra = chain_support(geometry, by_segment, points) if support else None
    return choose_hypotheses(geometry, by_segment, len(points), extra)[0].point


def test_support_reads_the_plate_right_where_its_own_markers_cannot() -> None:
    """Over random poses: without support the order is a guess among six (about 1 in 6
    right); with it, wrong only where a wrong reading's centre also meets the pair by chance."""
    geometry = _geometry()
    poses = range(60)
    right = [np.array_equal(_plate_choice(geometry, _frame(seed), support=True), np.arange(3)) for seed in poses]
    guessed = [np.array_equal(_plate_choice(geometry, _frame(seed), support=False), np.arange(3)) for seed in poses]
    assert np.mean(guessed) <= 0.4
    assert np.mean(right) >= 0.9


@pytest.mark.parametrize("seed", range(4))
def test_identification_names_plate_and_pair(seed: int) -> None:
    found = identify(_geometry(), _frame(seed))
    assert np.array_equal(found.point, np.arange(5))


def test_support_counts_only_pairs_that_get_a_pose() -> None:
    geometry = _geometry()
    points = _frame(0)[:4]  # one rod marker left: one sphere, no pose
    distance = cdist(points, points)
    by_segment = [segment_hypotheses(s, segment, points, distance) for s, segment in enumerate(geometry.segments)]
    assert all(value == 0 for value in chain_support(geometry, by_segment, points)[0])


def test_a_reading_with_fewer_inliers_than_the_best_is_not_credited() -> None:
    geometry = _geometry()
    points = _frame(1)
    distance = cdist(points, points)
    by_segment = [segment_hypotheses(s, segment, points, distance) for s, segment in enumerate(geometry.segments)]
    at = next(i for i, h in enumerate(by_segment[0]) if np.array_equal(h.point, np.arange(3)))  # rows are distinct
    short = Hypothesis(0, by_segment[0][at].pose, np.array([0, 1, -1]), 0.0)  # the true pose, one inlier short
    by_segment[0] = [*by_segment[0], short]
    support = chain_support(geometry, by_segment, points)[0]
    assert support[at] == 2
    assert support[-1] == 0
