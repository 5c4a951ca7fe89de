"""A pair placed about a joint centre that is itself uncertain (``place_by_joint(slack=...)``)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from formulations.subject.geometry import SegmentGeometry
from formulations.subject.joint_place import place_by_joint

PAIR = np.array([[0.0, 0.0, -90.0], [0.0, 60.0, -170.0]])  # its centre at the origin
ROD = SegmentGeometry("rod", np.arange(2), PAIR - PAIR.mean(axis=0), np.ones(2), np.full(2, 6.0))


def _scene(seed: int, off: float) -> tuple[np.ndarray, np.ndarray]:
    """The pair's points, ghosts far away, and the centre given ``off`` mm from the truth along the rod."""
    rng = np.random.default_rng(seed)
    turn = Rotation.random(random_state=rng).as_matrix()
    centre = rng.normal(0, 300, 3)
    points = np.concatenate([PAIR @ turn.T + centre, centre + rng.normal(0, 600, (4, 3))])
    axis = turn @ np.array([0.0, 0.0, 1.0])
    return points, centre + off * axis


def test_a_centre_off_by_more_than_the_tolerance_places_the_pair_only_with_slack() -> None:
    for seed in range(5):
        points, given = _scene(seed, off=12.0)
        free = np.ones(len(points), bool)
        pose, taken = place_by_joint(ROD, -PAIR.mean(axis=0), given, points, free)
        assert pose is None and not (taken >= 0).all()
        pose, taken = place_by_joint(ROD, -PAIR.mean(axis=0), given, points, free, slack=12.0)
        assert pose is not None
        assert np.array_equal(taken, [0, 1])


def test_slack_does_not_place_a_pair_whose_markers_are_too_far_apart() -> None:
    points, given = _scene(0, off=0.0)
    points[1] += 20.0 * (points[1] - points[0]) / np.linalg.norm(points[1] - points[0])  # the rod stretched
    pose, _ = place_by_joint(ROD, -PAIR.mean(axis=0), given, points, np.ones(len(points), bool), slack=30.0)
    assert pose is None
