"""The window's expected steps: a running median of the guide's steps (``markers.step_motion``)."""

from dataclasses import replace

import numpy as np
import pytest
from service_fixtures import generated_capture

import service.labeling.cloud as cloud_module
from formulations.markers.guide import GuideTrack
from formulations.markers.step_motion import HALF_WIDTH, expected_steps, masked_median, noise_dominated
from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling

TRUE_STEP = np.array([5.0, 0.0, 0.0])


def _tracked(positions: np.ndarray, unseen: np.ndarray | None = None) -> GuideTrack:
    """The guide that picked ``positions`` ``(M, N, 3)`` (frames 0..M-1 after the template at
    ``positions[0]``), each step expected to repeat the last one."""
    m, n, _ = positions.shape
    before = np.concatenate([positions[:1], positions[:1], positions[:-1]])
    velocity = before[1:] - before[:-1]  # into frame f: x(f-1) - x(f-2)
    velocity[0] = np.nan  # unknown right after the labeled frame
    predicted = np.concatenate([positions[:1], positions[:-1]]) + np.nan_to_num(velocity)
    return GuideTrack(
        predicted=predicted, radius=np.full((m, n), 60.0), velocity=velocity, tracked=np.ones((m, n), bool),
        unseen=np.zeros((m, n), int) if unseen is None else unseen, burst_var=np.ones((m, n)),
    )


def _walking(frames: int = 20, markers: int = 3, noise_mm: float = 2.0, seed: int = 4) -> np.ndarray:
    """Markers stepping ``TRUE_STEP`` a frame, with white noise."""
    rng = np.random.default_rng(seed)
    track = np.arange(frames)[:, None, None] * TRUE_STEP + np.arange(markers)[None, :, None] * 50.0
    return track + rng.normal(0.0, noise_mm, (frames, markers, 3))


def test_one_wrong_pick_does_not_move_the_expected_step() -> None:
    # The guide took a ghost 30 mm off marker 0's point in frame 6: its last steps into
    # frames 7 and 8 are off by about 30 mm, the median is not.
    positions = _walking()
    positions[6, 0, 2] += 30.0
    guide = _tracked(positions)
    steps = expected_steps(guide)
    assert np.abs(guide.velocity[7:9, 0, 2]).min() > 20.0
    assert np.linalg.norm(steps[7:9, 0] - TRUE_STEP, axis=1).max() < 6.0


def test_the_median_removes_noise_from_steady_motion() -> None:
    guide = _tracked(_walking(frames=40, noise_mm=2.0))
    steps = expected_steps(guide)
    raw_error = np.sqrt(np.mean((guide.velocity[4:-2] - TRUE_STEP) ** 2))
    median_error = np.sqrt(np.mean((steps[4:-2] - TRUE_STEP) ** 2))
    assert median_error < 0.7 * raw_error


def test_only_markers_whose_steps_vary_by_noise_are_smoothed() -> None:
    """A hand pushing a rim (100 mm circles every 8 frames) beside three steady markers, all
    with 2 mm noise: the hand keeps its last step."""
    turn = 2 * np.pi * np.arange(20)[:, None] / 8
    hand = np.hstack([100.0 * np.sin(turn), 100.0 * np.cos(turn), 60.0 * np.sin(2 * turn)])[:, None]
    positions = np.concatenate([_walking(), hand + np.random.default_rng(5).normal(0.0, 2.0, (20, 1, 3))], axis=1)
    guide = _tracked(positions)
    np.testing.assert_array_equal(noise_dominated(guide, guide.unseen == 0), [True, True, True, False])
    steps = expected_steps(guide)
    np.testing.assert_array_equal(steps[:, 3], guide.velocity[:, 3])
    assert not np.allclose(steps[2:, :3], guide.velocity[2:, :3])


def test_steps_after_a_gap_keep_the_neighbours_displacement() -> None:
    unseen = np.zeros((20, 3), int)
    unseen[8:10, 0] = [1, 2]
    guide = _tracked(_walking(), unseen)
    guide = replace(guide, velocity=guide.velocity.copy())
    guide.velocity[8:10, 0] = [[40.0, 0.0, 0.0], [-40.0, 0.0, 0.0]]  # what the neighbours imply while unseen
    steps = expected_steps(guide)
    np.testing.assert_array_equal(steps[8:10, 0], guide.velocity[8:10, 0])
    assert np.isnan(steps[0]).all()


def test_half_width_zero_is_the_guides_last_step() -> None:
    guide = _tracked(_walking())
    np.testing.assert_array_equal(expected_steps(guide, 0), guide.velocity)


def test_masked_median_skips_gaps_and_averages_an_even_count() -> None:
    values = np.array([[1.0, np.nan], [4.0, np.nan], [np.nan, np.nan]])
    np.testing.assert_array_equal(masked_median(values), [2.5, np.nan])


@pytest.mark.parametrize(("formulation", "half_width"), [("lp-l1", HALF_WIDTH), ("nn-hungarian", 0)])
def test_the_frame_by_frame_baseline_sees_no_later_frame(
    monkeypatch: pytest.MonkeyPatch, formulation: str, half_width: int,
) -> None:
    """nn-hungarian assigns each frame from the frames before it: its expected steps must not
    be medians over the frames after (the guide's last step instead), nor its unnamed tracks
    be born from them."""
    seen: list[tuple[int, bool]] = []
    original = cloud_module.cloud_candidates

    def recording(state, frames, gating, resources=None, around=None):
        seen.append((gating.step_median_frames, gating.unnamed_tracks))
        return original(state, frames, gating, resources, around)

    monkeypatch.setattr(cloud_module, "cloud_candidates", recording)
    capture = replace(generated_capture(25), unnamed_markers=1)
    CaptureLabeling(capture, LabelingOptions(formulation=formulation, second_pass=False)).label()
    assert seen and set(seen) == {(half_width, half_width > 0)}
