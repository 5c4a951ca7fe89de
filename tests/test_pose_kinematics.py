"""The kinematic tree: forward kinematics against hand-computed poses, joint limits, the subject-model body."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from formulations.errors import FormulationError
from formulations.pose.body import BodyModel, Node
from formulations.pose.from_subject import subject_body
from formulations.pose.human import Proportions, human_model
from formulations.pose.kinematics import forward_kinematics, marker_positions
from formulations.pose.rotation import sequential_rotation
from formulations.subject.model import Joint, Limb, Segment, SubjectModel

P = Proportions()


def _at(model: BodyModel, X: np.ndarray, name: str) -> np.ndarray:
    return forward_kinematics(model, X).positions[:, model.index(name)]


def _angle(model: BodyModel, X: np.ndarray, joint: str, axis: str, value: float, row: int = 0) -> None:
    node = model.nodes[model.index(joint)]
    X[row, model.columns[model.index(joint)] + node.axes.index(axis)] = value


def test_the_default_body_has_the_papers_33_dof_and_body_25b_names() -> None:
    model = human_model()
    assert model.dof == 33
    kinds = {node.name: node.kind for node in model.nodes}
    assert kinds["CHip"] == "root" and kinds["RHip"] == "socket" and kinds["RClavicle"] == "saddle"
    assert kinds["RKnee"] == "hinge" and kinds["RWrist"] == "fixed"


def test_rest_pose_and_translation_by_hand() -> None:
    model = human_model()
    X = np.zeros((1, model.dof))
    X[0, :3] = (1.0, 2.0, 3.0)
    root = np.array([1.0, 2.0, 3.0])
    assert np.allclose(_at(model, X, "RAnkle")[0], root + (0, -P.hip_half_width, -P.thigh - P.shank))
    wrist_height = P.trunk - P.shoulder_drop - P.upper_arm - P.forearm
    assert np.allclose(_at(model, X, "LWrist")[0], root + (0, P.shoulder_half_width, wrist_height))


def test_bent_knee_heading_and_abduction_by_hand_in_one_batch() -> None:
    model = human_model()
    X = np.zeros((3, model.dof))
    _angle(model, X, "RKnee", "y", np.pi / 2, row=0)  # shank swings straight back
    X[1, 3] = np.pi / 2  # heading: the body's left (+y) turns to -x
    _angle(model, X, "LShoulder", "x", np.pi / 2, row=2)  # left arm straight out to the side
    knee, ankle = _at(model, X, "RKnee"), _at(model, X, "RAnkle")
    assert np.allclose(ankle[0] - knee[0], (-P.shank, 0, 0))
    assert np.allclose(_at(model, X, "RHip")[1], (P.hip_half_width, 0, 0))
    assert np.allclose(_at(model, X, "LElbow")[2] - _at(model, X, "LShoulder")[2], (0, P.upper_arm, 0))
    assert np.allclose(ankle[1] - knee[1], (0, 0, -P.shank)) and np.allclose(ankle[2] - knee[2], (0, 0, -P.shank))


def test_sequential_rotation_is_the_intrinsic_euler_product() -> None:
    angles = np.random.default_rng(1).uniform(-3, 3, (20, 3))
    assert np.allclose(sequential_rotation("zyx", angles), Rotation.from_euler("ZYX", angles).as_matrix())
    assert np.allclose(sequential_rotation("zxy", angles), Rotation.from_euler("ZXY", angles).as_matrix())


def test_clip_keeps_every_angle_inside_its_limits() -> None:
    model = human_model()
    X = np.random.default_rng(2).uniform(-10, 10, (500, model.dof))
    clipped = model.clip(X)
    assert (clipped >= model.lower).all() and (clipped <= model.upper).all()
    inside = (model.lower <= X) & (model.upper >= X)
    assert np.array_equal(clipped[inside], X[inside])


def test_a_child_before_its_parent_is_refused() -> None:
    with pytest.raises(FormulationError, match="after its parent"):
        BodyModel((Node("root", -1, (0, 0, 0)), Node("a", 2, (0, 0, 1)), Node("b", 0, (0, 0, 1))))


def _two_segment_subject() -> SubjectModel:
    thigh = Segment("THI", ["T1", "T2", "T3"], [[0, 0, 0], [50, 0, 0], [0, 50, -200]], [1, 1, 1])
    shank = Segment("SHA", ["S1", "S2", "S3"], [[10, 0, 0], [60, 0, 0], [10, 50, -100]], [1, 1, 1])
    knee = Joint("KNE", ("THI", "SHA"), ([0, 0, -400], [10, 0, 100]), 1.0)
    return SubjectModel([thigh, shank], [knee], [Limb("THI", ("KNE", "KNE"), 0.0)], [])


def test_subject_body_reproduces_the_markers_and_turns_about_the_joint_centre() -> None:
    body = subject_body(_two_segment_subject(), metres_per_unit=1e-3)
    assert [n.kind for n in body.nodes] == ["root", "socket"] and body.dof == 9
    X = np.zeros((2, body.dof))
    X[1, 6 + 2] = np.pi / 2  # the knee's third axis, y: the shank swings back about the knee centre
    markers = marker_positions(body, forward_kinematics(body, X))
    assert np.allclose(markers[0, :3], [[0, 0, 0], [50, 0, 0], [0, 50, -200]])
    # In the thigh's frame the knee centre is (0, 0, -400); shank markers sit at centre + (S - (10, 0, 100)).
    local = np.array([[0, 0, -100], [50, 0, -100], [0, 50, -200]], dtype=float)
    assert np.allclose(markers[0, 3:], local + (0, 0, -400))
    turned = Rotation.from_euler("y", np.pi / 2).as_matrix() @ local.T
    assert np.allclose(markers[1, 3:], turned.T + (0, 0, -400))
