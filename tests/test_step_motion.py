"""The window's expected steps: a running median of the guide's steps (``markers.step_motion``)."""

import numpy as np
import pytest
from service_fixtures import generated_capture

import service.labeling.cloud as cloud_module
from formulations.markers.guide import GuideTrack
from formulations.markers.step_motion import HALF_WIDTH, expected_steps
from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling


def _guide(velocity: np.ndarray, unseen: np.ndarray) -> GuideTrack:
    m, n = unseen.shape
    return GuideTrack(
        predicted=np.zeros((m, n, 3)), radius=np.full((m, n), 60.0), velocity=velocity,
        tracked=unseen == 0, unseen=unseen, burst_var=np.ones((m, n)),
    )


def _steady(frames: int, acceleration: float = 0.0) -> np.ndarray:
    """``(frames, 1, 3)`` steps of a marker moving along x with constant acceleration."""
    steps = np.zeros((frames, 1, 3))
    steps[:, 0, 0] = 5.0 + acceleration * np.arange(frames)
    steps[:, 0, 1] = -2.0
    return steps


def test_one_wrong_pick_does_not_move_the_expected_step() -> None:
    # A ghost 30 mm off taken in frame 6 makes the guide's steps into frames 6 and 7 jump
    # by +30 and -30 mm: the raw steps are off there, the median is not.
    velocity = _steady(12)
    velocity[6, 0, 2] += 30.0
    velocity[7, 0, 2] -= 30.0
    unseen = np.zeros((12, 1), int)
    steps = expected_steps(_guide(velocity, unseen))
    assert np.abs(velocity[6:8, 0, 2]).max() == 30.0
    np.testing.assert_allclose(steps, _steady(12), atol=1e-9)


def test_steady_acceleration_is_not_smoothed_away() -> None:
    velocity = _steady(10, acceleration=3.0)
    steps = expected_steps(_guide(velocity, np.zeros((10, 1), int)))
    np.testing.assert_allclose(steps[2:-2], velocity[2:-2], atol=1e-9)
    # Within h of the window's ends only the frames inside count: off by at most h a.
    assert np.abs(steps - velocity).max() <= 2 * 3.0 + 1e-9


def test_steps_after_a_gap_keep_the_neighbours_displacement() -> None:
    velocity = _steady(8)
    velocity[3:5, 0] = [[40.0, 0.0, 0.0], [-40.0, 0.0, 0.0]]  # what the neighbours imply while unseen
    velocity[0, 0] = np.nan  # unknown right after the labeled frame
    unseen = np.zeros((8, 1), int)
    unseen[3:5, 0] = [1, 2]
    steps = expected_steps(_guide(velocity, unseen))
    np.testing.assert_array_equal(steps[3:5], velocity[3:5])
    assert np.isnan(steps[0]).all()
    np.testing.assert_allclose(steps[5:], _steady(8)[5:], atol=1e-9)


def test_median_of_an_even_count_is_the_mean_of_the_middle_two() -> None:
    velocity = np.zeros((2, 1, 3))
    velocity[:, 0, 0] = [1.0, 4.0]
    steps = expected_steps(_guide(velocity, np.zeros((2, 1), int)))
    np.testing.assert_allclose(steps[:, 0, 0], [2.5, 2.5])


def test_half_width_zero_is_the_guides_last_step() -> None:
    velocity = _steady(6)
    velocity[2, 0, 2] += 30.0
    np.testing.assert_array_equal(expected_steps(_guide(velocity, np.zeros((6, 1), int)), 0), velocity)


@pytest.mark.parametrize(("formulation", "half_width"), [("lp-l1", HALF_WIDTH), ("nn-hungarian", 0)])
def test_the_frame_by_frame_baseline_sees_no_later_frame(
    monkeypatch: pytest.MonkeyPatch, formulation: str, half_width: int,
) -> None:
    """nn-hungarian assigns each frame from the frames before it: its expected steps must not
    be medians over the frames after (the guide's last step instead)."""
    seen: list[int] = []
    original = cloud_module.cloud_candidates

    def recording(state, frames, gating, resources=None):
        seen.append(gating.step_median_frames)
        return original(state, frames, gating, resources)

    monkeypatch.setattr(cloud_module, "cloud_candidates", recording)
    CaptureLabeling(generated_capture(25), LabelingOptions(formulation=formulation, second_pass=False)).label()
    assert seen and set(seen) == {half_width}
