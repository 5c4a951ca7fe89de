"""A joint's rest orientation tells a near-isosceles marker pair's two readings apart."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.errors import FormulationError
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import identify
from formulations.subject.joint_rest import rest_rotation, turned_from
from formulations.subject.model import Joint, Segment, SubjectModel

UPPER = [[60.0, 0.0, 0.0], [-40.0, 45.0, 0.0], [-20.0, -50.0, 10.0], [0.0, 10.0, -60.0]]
WRIST = [[25.0, 0.0, 0.0], [-25.0, 0.0, 0.0]]  # both 250 mm from the elbow: isosceles
ELBOW_IN_UPPER, ELBOW_IN_FOREARM = [0.0, 0.0, -250.0], [0.0, 0.0, 250.0]
REST = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()


def _model(rest: np.ndarray | None) -> SubjectModel:
    segments = [Segment("upper", ["U0", "U1", "U2", "U3"], UPPER, [1.0] * 4),
                Segment("forearm", ["Med", "Lat"], WRIST, [1.0, 1.0])]
    joint = Joint("upper-forearm", ("upper", "forearm"), (ELBOW_IN_UPPER, ELBOW_IN_FOREARM), 2.0,
                  None if rest is None else rest.tolist())
    return SubjectModel(segments, [joint], [], [])


def _frame(flexion_deg: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Shuffled points of the six markers, the forearm bent ``flexion_deg`` from rest about an
    axis across it; each point's marker index (model order)."""
    rng = np.random.default_rng(seed)
    r_a = Rotation.random(random_state=seed).as_matrix()
    d_a = rng.uniform(-500, 500, 3)
    r_b = r_a @ REST @ Rotation.from_rotvec([np.radians(flexion_deg), 0.0, 0.0]).as_matrix()
    elbow = r_a @ ELBOW_IN_UPPER + d_a
    d_b = elbow - r_b @ ELBOW_IN_FOREARM
    truth = np.concatenate([np.array(UPPER) @ r_a.T + d_a, np.array(WRIST) @ r_b.T + d_b])
    order = rng.permutation(len(truth))
    return truth[order], order


def test_rest_rotation_is_the_mean_relative_rotation_over_the_frames_posing_both() -> None:
    rng = np.random.default_rng(0)
    r_a = Rotation.random(200, random_state=1).as_matrix()
    wobble = Rotation.from_rotvec(rng.normal(0, 0.05, (200, 3))).as_matrix()
    r_b = np.einsum("kij,jl,klm->kim", r_a, REST, wobble)
    r_a[:20] = np.nan  # frames where one segment has no pose are left out
    q = np.array(rest_rotation(r_a, r_b))
    assert np.degrees(turned_from(REST, q)) < 1.0
    assert np.allclose(q @ q.T, np.eye(3), atol=1e-3) and np.linalg.det(q) > 0
    assert rest_rotation(np.full((3, 3, 3), np.nan), r_b[:3]) is None


@pytest.mark.parametrize("seed", range(4))
def test_a_pair_as_far_from_its_joint_as_each_other_is_named_by_the_rest_orientation(seed: int) -> None:
    points, marker = _frame(35.0, seed)
    without = identify(ModelGeometry.of(_model(None)), points)
    assert (without.point[4:] == -1).all(), "the two readings tie: without a rest orientation nothing is named"
    found = identify(ModelGeometry.of(_model(REST)), points)
    assert np.array_equal(marker[found.point], np.arange(6))


def test_a_joint_turned_far_from_rest_leaves_the_pair_unnamed_rather_than_guess() -> None:
    points, _ = _frame(120.0, 0)  # the readings are 120 and 180 degrees from rest: less than a quarter turn apart
    found = identify(ModelGeometry.of(_model(REST)), points)
    assert (found.point[4:] == -1).all()
    assert (found.point[:4] >= 0).all()


def test_the_rest_orientation_survives_the_json_and_old_models_load_without_it() -> None:
    model = _model(REST)
    again = SubjectModel.from_json(model.to_json())
    assert np.allclose(again.joints[0].rest, REST)
    old = json.loads(model.to_json())
    del old["joints"][0]["rest"]
    assert SubjectModel.from_json(json.dumps(old)).joints[0].rest is None
    old["joints"][0]["rest"] = [[1.0, 0.0], [0.0, 1.0]]
    with pytest.raises(FormulationError, match="rest is not a 3 x 3 rotation"):
        SubjectModel.from_json(json.dumps(old))
