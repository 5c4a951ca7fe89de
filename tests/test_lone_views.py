"""joint-3d: a filled marker that one camera still sees is put on that camera's ray (issue 12, fill)."""

import numpy as np

from formulations.cameras.camera import Camera
from formulations.cameras.lone_views import fills_on_lone_views
from formulations.cameras.rig import Rig

K = [[1000.0, 0, 960], [0, 1000.0, 540], [0, 0, 1]]
RIG = Rig.of([
    Camera.from_rvec(K, np.zeros(5), [0.0, 2 * np.pi * c / 4, 0.0], [0.0, 0.0, 3000.0], (1920, 1080), f"c{c}")
    for c in range(4)
])
TRUE = np.array([[10.0, 20.0, 30.0], [300.0, -100.0, 50.0]])  # marker 0 filled, marker 1 labeled
FILL = TRUE[0] + [30.0, -25.0, 20.0]  # a fill 45 mm off


def _frame(views: dict[int, np.ndarray], used: dict[int, bool]) -> tuple[list, list]:
    """One frame's normalised detections per camera (the given world points' images) and their used flags."""
    normalised, flags = [], []
    for c in range(4):
        points = views.get(c, np.zeros((0, 3)))
        normalised.append(RIG.image_plane(points)[0][c] if len(points) else np.zeros((0, 2)))
        flags.append(np.full(len(points), used.get(c, False)))
    return normalised, flags


def _filled(normalised: list, used: list) -> np.ndarray:
    filled = np.full((1, 2, 3), np.nan)
    filled[0, 0] = FILL
    labeled = np.full((1, 2, 3), np.nan)
    labeled[0, 1] = TRUE[1]
    return fills_on_lone_views(filled, np.array([[True, False]]), labeled, RIG, [normalised], [used])[0, 0]


def test_a_marker_one_camera_sees_is_put_on_that_ray():
    normalised, used = _frame({1: TRUE[[0]]}, {})
    placed = _filled(normalised, used)
    ray = (TRUE[0] - RIG.centres[1]) / np.linalg.norm(TRUE[0] - RIG.centres[1])
    # The view removes the fill's error across the ray; only its depth along the ray is left.
    left = np.linalg.norm(placed - TRUE[0])
    assert abs(left - abs(ray @ (FILL - TRUE[0]))) < 1e-6 and left < 0.7 * np.linalg.norm(FILL - TRUE[0])
    # On camera 1's ray through the detection: its image is the detection.
    assert np.allclose(RIG.image_plane(placed[None])[0][1, 0], normalised[1][0], atol=1e-9)


def test_used_explained_far_or_twice_seen_detections_leave_the_fill_alone():
    used_elsewhere = _frame({1: TRUE[[0]]}, {1: True})  # a labeled point uses it
    explained = _frame({1: TRUE[[1]]}, {})  # the labeled marker's own view, unused by its point
    far = _frame({1: TRUE[[0]] + [0.0, 0.0, 400.0]}, {})  # 400 mm off: outside the gate
    twice = _frame({1: TRUE[[0]], 2: TRUE[[0]]}, {})  # two views that made no 3D point: suspect
    for normalised, used in (used_elsewhere, explained, far, twice):
        assert np.array_equal(_filled(normalised, used), FILL)
