"""The demo scene is deterministic and physically plausible."""

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from service.errors import InputError
from service.evaluation.scene import generate_scene

SEEDS = (0, 1, 2)


def test_same_seed_gives_identical_scene() -> None:
    a, b = generate_scene(seed=3), generate_scene(seed=3)
    assert a.names == b.names
    np.testing.assert_array_equal(a.positions, b.positions)


def test_different_seeds_differ() -> None:
    a, b = generate_scene(seed=0), generate_scene(seed=1)
    assert a.names == b.names
    assert np.abs(a.positions - b.positions).max() > 10.0


def test_shape_and_names() -> None:
    scene = generate_scene()
    assert scene.positions.shape == (600, len(scene.names), 3)
    assert 36 <= len(scene.names) <= 41
    assert len(set(scene.names)) == len(scene.names)
    for name in ("LFHD", "RFHD", "C7", "CLAV", "LWRA", "RFIN", "LASI", "RKNE", "LHEE", "RTOE"):
        assert name in scene.names
    assert scene.rate == 120.0


def test_no_missing_samples() -> None:
    scene = generate_scene()
    assert not np.isnan(scene.positions).any()
    assert not scene.missing().any()


@pytest.mark.parametrize("seed", SEEDS)
def test_markers_stay_apart(seed: int) -> None:
    positions = generate_scene(seed=seed).positions
    closest = np.min([pdist(frame) for frame in positions], axis=0)
    assert closest.min() >= 30.0
    assert np.mean(closest >= 40.0) >= 0.95


@pytest.mark.parametrize("seed", SEEDS)
def test_speeds_are_human(seed: int) -> None:
    scene = generate_scene(seed=seed)
    step = np.linalg.norm(np.diff(scene.positions, axis=0), axis=2)
    assert 15.0 <= step.max() <= 35.0  # mm per frame at 120 Hz
    pelvis = [scene.names.index(n) for n in ("LASI", "RASI", "LPSI", "RPSI")]
    travel = scene.positions[:, pelvis, 0].mean(axis=1)
    walking_speed = (travel[-1] - travel[0]) / (scene.n_frames - 1) * scene.rate
    assert 1000.0 <= walking_speed <= 1400.0  # mm/s


def test_z_is_up_and_feet_stay_above_floor() -> None:
    scene = generate_scene()
    z = scene.positions[..., 2]
    assert (z[:, scene.names.index("LFHD")] > z[:, scene.names.index("LTOE")] + 1000.0).all()
    assert z.min() >= 0.0


def test_frames_and_rate_respected() -> None:
    full = generate_scene(n_frames=600, seed=5)
    short = generate_scene(n_frames=37, seed=5)
    assert short.positions.shape[0] == 37
    np.testing.assert_allclose(short.positions, full.positions[:37])
    assert generate_scene(n_frames=10, rate=240.0).rate == 240.0


@pytest.mark.parametrize("n_frames, rate", [(0, 120.0), (10, 0.0)])
def test_bad_arguments_raise(n_frames: int, rate: float) -> None:
    with pytest.raises(InputError):
        generate_scene(n_frames=n_frames, rate=rate)
