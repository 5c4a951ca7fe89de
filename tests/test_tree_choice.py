"""One hypothesis (or none) per segment, chosen jointly over the skeleton (``tree_choice``):
the dynamic programme against brute force over every combination, on small random trees."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.subject.constellation import Hypothesis, Pose
from formulations.subject.geometry import JointGeometry, ModelGeometry, SegmentGeometry
from formulations.subject.tree_choice import choose_hypotheses

POINTS = 5  # few: hypotheses of jointed segments often share one
TOLERANCE = 60.0  # mm, at the joints
PARENT = (None, 0, 1, 1)  # a chain 0-1-2 with a branch 1-3


def _geometry(rng: np.random.Generator) -> ModelGeometry:
    segments = [SegmentGeometry(f"s{s}", np.arange(3 * s, 3 * s + 3), rng.normal(0, 50, (3, 3)), np.ones(3),
                                np.full(3, 5.0)) for s in range(len(PARENT))]
    joints = [JointGeometry(p, s, rng.normal(0, 40, 3), rng.normal(0, 40, 3), TOLERANCE, 3.0)
              for s, p in enumerate(PARENT) if p is not None]
    return ModelGeometry([f"m{i}" for i in range(3 * len(PARENT))], segments, joints, [],
                         np.repeat(np.arange(len(PARENT)), 3), 5.0, 3.0)


def _hypotheses(rng: np.random.Generator, segment: int) -> list[Hypothesis]:
    """0-4 hypotheses with poses near one another (so joints meet about half the time)."""
    out = []
    for _ in range(int(rng.integers(0, 5))):
        point = np.full(3, -1)
        taken = int(rng.integers(1, 4))
        point[:taken] = rng.choice(POINTS, taken, replace=False)
        pose = Pose(Rotation.random(random_state=rng).as_matrix(), rng.normal(0, 25, 3))
        out.append(Hypothesis(segment, pose, point, float(rng.uniform(0, 8))))
    return out


def _score(geometry: ModelGeometry, choice: dict[int, Hypothesis]) -> float | None:
    """The objective of ``tree_choice``'s module doc, None where a joint forbids the choice."""
    for joint in geometry.joints:
        if joint.a in choice and joint.b in choice:
            a, b = choice[joint.a], choice[joint.b]
            if np.linalg.norm(a.pose.place(joint.centre_a[None]) - b.pose.place(joint.centre_b[None])) > joint.tolerance:
                return None
            if np.intersect1d(a.point[a.point >= 0], b.point[b.point >= 0]).size:
                return None
    return sum(h.inliers - h.rms / (2 * float(geometry.segments[s].tolerance.mean())) for s, h in choice.items())


@pytest.mark.parametrize("seed", range(40))
def test_the_choice_is_the_best_combination(seed: int) -> None:
    rng = np.random.default_rng(seed)
    geometry = _geometry(rng)
    by_segment = [_hypotheses(rng, s) for s in range(len(PARENT))]
    scores = []
    for picks in product(*[[*h, None] for h in by_segment]):
        score = _score(geometry, {s: h for s, h in enumerate(picks) if h is not None})
        if score is not None:
            scores.append(score)
    chosen = choose_hypotheses(geometry, by_segment, POINTS)
    assert _score(geometry, chosen) == pytest.approx(max(scores))
