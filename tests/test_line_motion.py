"""The least turn that takes one line of points onto another (``formulations.markers.rigid.line_motion``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.markers.rigid import line_motion

LINE = np.array([[0.0, 0.0, 0.0], [70.0, 0.0, 0.0], [250.0, 0.0, 0.0]])


@pytest.mark.parametrize("seed", range(8))
def test_it_maps_the_line_and_turns_no_more_than_the_angle_between_the_lines(seed):
    rng = np.random.default_rng(seed)
    turn = Rotation.from_rotvec(rng.normal(0.0, 0.8, 3))
    source = LINE[None]
    target = turn.apply(LINE)[None] + rng.normal(0.0, 100.0, 3)
    rotation, c_s, c_t = line_motion(source, target, np.ones((1, 3)))
    # each point onto its own (the best-fit directions' signs are arbitrary: they are matched)
    assert np.allclose((source[0] - c_s[0]) @ rotation[0].T + c_t[0], target[0], atol=1e-6)
    assert np.allclose(rotation[0] @ rotation[0].T, np.eye(3), atol=1e-9) and np.linalg.det(rotation[0]) == pytest.approx(1.0)
    # Any rotation mapping the line is this one composed with a turn about the line; the
    # least has the angle between the two directions, which no other reaches below.
    between = np.arccos(np.clip(turn.apply([1.0, 0.0, 0.0])[0], -1.0, 1.0))
    assert Rotation.from_matrix(rotation[0]).magnitude() == pytest.approx(between, abs=1e-9)
    assert turn.magnitude() >= between - 1e-9

