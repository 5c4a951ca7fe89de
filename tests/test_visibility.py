"""Occlusion-aware P_D (Ringer & Lasenby 2002, eq. 8): ray against capsules, blurry edges.

The simulator (``service.evaluation.simulate_cameras``) occludes by a Markov chain per
(camera, marker), not by the body, so P_D is judged on a constructed scene instead: a
walking, turning figure of elliptic cylinders ringed by cameras, markers on the skin, a
marker hidden where a sampled ray from it to the camera enters any cylinder, and seen with
probability 0.95 otherwise. The capsule body under test (circular, from a subject model or
from the markers alone) is not the figure's (elliptic), and the truth is found by sampling,
not by the closed-form distance.
"""

import numpy as np
import pytest
from scipy.stats import rankdata

from formulations.cameras.visibility import Body, blur, detection_probability, segment_distance, smooth_step
from formulations.cameras.visibility_body import marker_capsules, rigid_neighbours, segment_capsules
from formulations.subject.model import Joint, Segment, SubjectModel

M = 7.0  # marker radius, mm
LAMBDA = 0.95

# segment: (parent joint or None, offset of its proximal joint in the parent's frame, length, a, b, base direction)
FIGURE = {
    "torso": (None, (0, 0, 0), 520, 150, 95, 1),
    "thigh_l": ("torso", (0, 100, 0), 450, 80, 72, -1),
    "shank_l": ("thigh_l", (0, 0, -450), 440, 55, 50, -1),
    "thigh_r": ("torso", (0, -100, 0), 450, 80, 72, -1),
    "shank_r": ("thigh_r", (0, 0, -450), 440, 55, 50, -1),
    "arm_l": ("torso", (0, 200, 480), 300, 48, 44, -1),
    "forearm_l": ("arm_l", (0, 0, -300), 280, 40, 36, -1),
    "arm_r": ("torso", (0, -200, 480), 300, 48, 44, -1),
    "forearm_r": ("arm_r", (0, 0, -300), 280, 40, 36, -1),
}
MARKERS_PER_SEGMENT = 4


def _rotation(yaw, pitch):
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    return rz @ ry


def _pitch(name, f):
    swing = 0.6 * np.sin(2 * np.pi * f / 30)
    side = 1 if name.endswith("_l") else -1
    return {"torso": 0.0, "thigh": side * swing, "shank": side * swing - 0.4 * (1 + np.sin(2 * np.pi * f / 30)),
            "arm": -side * swing, "forearm": -side * swing + 0.5}[name.split("_")[0]]


def _marker_local(name):
    _, _, length, a, b, base = FIGURE[name]
    rng = np.random.default_rng(sum(map(ord, name)))
    phi = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(MARKERS_PER_SEGMENT) / MARKERS_PER_SEGMENT
    h = base * length * rng.uniform(0.2, 0.8, MARKERS_PER_SEGMENT)
    return np.column_stack([(a + M) * np.cos(phi), (b + M) * np.sin(phi), h])


def _figure(n_frames):
    """Per frame: segment poses {name: (joint, R)}; and ``(F, N, 3)`` markers."""
    poses, markers = [], []
    for f in range(n_frames):
        yaw, root = 2 * np.pi * f / n_frames, np.array([10.0 * f, 0, 1000])
        pose = {}
        for name, (parent, offset, *_rest) in FIGURE.items():
            r = _rotation(yaw, _pitch(name, f))
            joint = root if parent is None else pose[parent][0] + pose[parent][1] @ np.array(offset, float)
            pose[name] = (joint, r)
        poses.append(pose)
        markers.append(np.vstack([pose[n][0] + _marker_local(n) @ pose[n][1].T for n in FIGURE]))
    return poses, np.array(markers)


def _cameras():
    angle = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    return np.column_stack([4000 * np.cos(angle), 4000 * np.sin(angle), 1200 + 600 * (np.arange(6) % 2)])


def _hidden(pose, markers, centres):
    """``(N, C)`` True where the sampled ray from the marker to the camera enters a cylinder."""
    t = np.linspace(0, 1, 626)[1:] * 2500 / np.linalg.norm(centres[None] - markers[:, None], axis=2)[..., None]
    rays = markers[:, None, None] + t[..., None] * (centres[None, :, None] - markers[:, None, None])
    hidden = np.zeros(t.shape[:2], dtype=bool)
    for name, (joint, r) in pose.items():
        _, _, length, a, b, base = FIGURE[name]
        local = (rays - joint) @ r
        along = base * local[..., 2]
        inside = (along >= 0) & (along <= length) & ((local[..., 0] / a) ** 2 + (local[..., 1] / b) ** 2 < 1)
        hidden |= inside.any(axis=2)
    return hidden


def _scene_model():
    k = MARKERS_PER_SEGMENT
    segments = [Segment(n, [f"{n}{i}" for i in range(k)], _marker_local(n).tolist(), [1.0] * k) for n in FIGURE]
    joints = [Joint(f"{parent}-{n}", (parent, n), (list(map(float, offset)), [0.0, 0.0, 0.0]), 1.0)
              for n, (parent, offset, *_rest) in FIGURE.items() if parent is not None]
    return SubjectModel(segments, joints, [], [], M), [m for s in segments for m in s.markers]


@pytest.fixture(scope="module")
def scene():
    poses, markers = _figure(24)
    centres = _cameras()
    rng = np.random.default_rng(0)
    hidden = np.array([_hidden(p, x, centres) for p, x in zip(poses, markers)])
    detected = ~hidden & (rng.random(hidden.shape) < LAMBDA)
    return markers, centres, detected


def _auc(score, label):
    ranks = rankdata(score)
    positive = label.sum()
    return (ranks[label].sum() - positive * (positive + 1) / 2) / (positive * (len(label) - positive))


def _log_loss(p, label):
    p = np.clip(p, 0.01, 0.99)  # eq. 8's exact 0 is never calibrated
    return -np.mean(np.where(label, np.log(p), np.log1p(-p)))


def test_segment_distance_matches_dense_sampling():
    """Sample one segment densely; each sample's distance to the other is the projection clamped."""
    rng = np.random.default_rng(1)
    p1, q1, p2, q2 = (rng.normal(0, 1, (100, 3)) for _ in range(4))
    q2[:20] = p2[:20]  # spheres
    q1[20:30] = p1[20:30] + 1e-3 * (q2[20:30] - p2[20:30])  # near-parallel, short
    q1[30:40] = p1[30:40] + 2 * (q2[30:40] - p2[30:40])  # parallel
    s = np.linspace(0, 1, 10001)
    a = p1[:, None] + s[None, :, None] * (q1 - p1)[:, None]
    d2 = (q2 - p2)[:, None]
    t = np.clip(np.einsum("psd,pud->ps", a - p2[:, None], d2) / np.maximum(np.einsum("pud,pud->pu", d2, d2), 1e-300), 0, 1)
    sampled = np.linalg.norm(a - p2[:, None] - t[..., None] * d2, axis=2).min(axis=1)
    exact = segment_distance(p1, q1, p2, q2)
    assert np.all(exact <= sampled + 1e-9)
    assert np.allclose(exact, sampled, atol=2e-3)


def test_a_ray_through_a_cylinder_is_hidden_a_clear_ray_is_lambda_and_the_edge_is_monotone():
    body = Body(start=np.array([[0.0, 0, -300]]), end=np.array([[0.0, 0, 300]]), radius=np.array([50.0]))
    marker = np.array([[0.0, -500, 0]])
    sideways = np.linspace(-1500, 1500, 601)
    cameras = np.column_stack([sideways, np.full_like(sideways, 3000), np.zeros_like(sideways)])
    p = detection_probability(body, marker, cameras, LAMBDA, blur(M, 5.0))[0]
    # the distance of the axis (the origin, in plan) from the line through (0, -500) and (x, 3000)
    clearance = 500 * np.abs(sideways) / np.hypot(sideways, 3500) - 50
    assert p[sideways == 0] < 1e-12
    assert np.allclose(p[clearance > blur(M, 5.0)], LAMBDA)
    inward = clearance.argsort()
    assert np.all(np.diff(p[inward]) >= -1e-12) and 0 < p[np.abs(clearance) < 2].min() < LAMBDA
    assert np.all(np.diff(smooth_step(np.linspace(-2, 2, 101))) >= 0)


def test_a_marker_on_its_own_limb_is_seen_from_the_front_and_hidden_from_behind():
    body = Body(start=np.array([[0.0, 0, -300]]), end=np.array([[0.0, 0, 300]]), radius=np.array([60.0]))
    marker = np.array([[0.0, 60 + M, 0]])  # on the skin, facing +y
    cameras = np.array([[0.0, 3000, 0], [3000.0, 60 + M, 0], [0.0, -3000, 0]])  # in front, grazing, behind
    p = detection_probability(body, marker, cameras, LAMBDA, blur(M))[0]
    assert p[0] == pytest.approx(LAMBDA) and p[1] == pytest.approx(LAMBDA) and p[2] < 1e-12


def test_occlusion_aware_p_d_predicts_the_undetected_pairs_better_than_a_constant(scene):
    markers, centres, detected = scene
    model, names = _scene_model()
    capsules = segment_capsules(model, names)
    neighbours = rigid_neighbours(markers, 3, rigid_sd=2.0)
    edge = blur(M, 10.0)
    by_model = np.array([detection_probability(capsules.at(x), x, centres, LAMBDA, edge) for x in markers])
    by_markers = np.array([detection_probability(marker_capsules(x, neighbours, M), x, centres, LAMBDA, edge) for x in markers])
    label = detected.ravel()
    assert 0.15 < 1 - label.mean() < 0.6  # the scene hides a fair share
    constant = _log_loss(np.full(label.shape, label.mean()), label)  # the best constant lambda_D
    for p, least_auc in ((by_model, 0.85), (by_markers, 0.7)):
        assert _auc(p.ravel(), label) > least_auc
        assert _log_loss(p.ravel(), label) < constant
    assert _auc(by_model.ravel(), label) > _auc(by_markers.ravel(), label)


def test_segment_capsules_follow_the_segment():
    model, names = _scene_model()
    capsules = segment_capsules(model, names)
    poses, markers = _figure(3)
    body = capsules.at(markers[2])
    joint, r = poses[2]["thigh_l"]
    thigh = [s.name for s in model.segments].index("thigh_l")
    axis = np.array([body.start[thigh], body.end[thigh]])
    expected = joint + np.array([[0, 0, 0], [0, 0, -450.0]]) @ r.T  # hip and knee
    assert np.allclose(np.sort(np.linalg.norm(axis - expected[0], axis=1)), [0, 450], atol=1e-6)
    assert 60 < body.radius[thigh] < 80
    hidden = markers[2].copy()
    hidden[capsules.markers[thigh, :2]] = np.nan  # two known: the segment cannot be posed
    assert len(capsules.at(hidden).radius) == len(model.segments) - 1
