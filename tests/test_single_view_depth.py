"""A marker seen by one camera takes its depth along the ray from the markers rigid with it (issue 12, fill)."""

import numpy as np

from formulations.cameras.per_camera.single_view import single_views_on_rays

# Four markers of one rigid segment (mm), no three on a line.
BODY = np.array([[0.0, 0.0, 0.0], [90.0, 10.0, 0.0], [20.0, 80.0, 15.0], [40.0, 30.0, 70.0]])
CAMERA = np.array([300.0, -4000.0, 1500.0])


def _moving_body(frames: int = 40) -> np.ndarray:
    """``(F, 4, 3)``: the segment turning about z and sliding, as a swinging limb."""
    out = np.empty((frames, len(BODY), 3))
    for t in range(frames):
        a = 0.05 * t
        turn = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        out[t] = BODY @ turn.T + [12.0 * t, 3.0 * t, 800.0]
    return out


def _one_view(truth: np.ndarray, frames: slice, depth_error: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Marker 0 seen by CAMERA alone over ``frames``, located ``depth_error`` mm off along its ray."""
    positions = truth.copy()
    single = np.zeros(truth.shape[:2], bool)
    single[frames, 0] = True
    direction = truth[frames, 0] - CAMERA
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    positions[frames, 0] += depth_error * direction
    return positions, single, direction


def test_single_view_sightings_move_along_their_rays_to_the_rigid_donors():
    truth = _moving_body()
    positions, single, direction = _one_view(truth, slice(15, 24), depth_error=55.0)
    no_fill = np.full_like(truth, np.nan)
    origin = np.repeat(CAMERA[None], single.sum(), axis=0)
    assert np.linalg.norm(positions[single] - truth[single], axis=1).min() > 50.0  # the setup: 55 mm off
    placed = single_views_on_rays(positions, no_fill, single, origin, direction)
    assert np.linalg.norm(placed[single] - truth[single], axis=1).max() < 1.0
    assert np.array_equal(placed[~single], positions[~single])  # triangulated markers untouched
    # Only the depth changed: each placed point is still on its own ray.
    offset = placed[single] - CAMERA
    assert np.allclose(np.cross(offset, direction), 0.0, atol=1e-6)


def test_without_donors_the_depth_is_tied_to_the_triangulated_sightings_around():
    truth = _moving_body()
    alone = truth[:, :1]  # one marker: no segment-mates to take a depth from
    positions, single, direction = _one_view(alone, slice(15, 24), depth_error=55.0)
    origin = np.repeat(CAMERA[None], single.sum(), axis=0)
    placed = single_views_on_rays(positions, np.full_like(alone, np.nan), single, origin, direction)
    before = np.linalg.norm(positions[single] - alone[single], axis=1)
    after = np.linalg.norm(placed[single] - alone[single], axis=1)
    assert (after <= before + 1e-9).all() and after.max() < before.max()
    assert np.allclose(np.cross(placed[single] - CAMERA, direction), 0.0, atol=1e-6)
