"""The reported confidence is calibrated: labels reported p-sure are right about p of the time."""

import numpy as np
from service_fixtures import generated_capture

from formulations.confidence.calibration import LABEL_CALIBRATION, fit_calibration
from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.stats import DOUBTFUL_BELOW, REPORTED_DOUBTFUL_BELOW, doubtful_labels, reported_doubtful


def _expected_calibration_error(p: np.ndarray, right: np.ndarray) -> float:
    edges = np.linspace(0.0, 1.0, 11)
    bins = np.clip(np.digitize(p, edges) - 1, 0, 9)
    return float(sum(abs(right[bins == b].mean() - p[bins == b].mean()) * (bins == b).mean()
                     for b in range(10) if (bins == b).any()))


def _under_confident(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Raw p with labels right at rate sqrt(p) (as the windows' p: right far more often than said)."""
    rng = np.random.default_rng(seed)
    raw = rng.beta(0.6, 0.3, n)
    return raw, rng.random(n) < np.sqrt(raw)


def test_a_fit_on_one_sample_calibrates_another():
    raw, right = _under_confident(40_000, 0)
    assert _expected_calibration_error(raw, right) > 0.05  # the setup: raw p says too little
    calibration = fit_calibration(raw, right)
    held_raw, held_right = _under_confident(40_000, 1)
    assert _expected_calibration_error(calibration(held_raw), held_right) < 0.01
    grid = np.linspace(0.05, 0.999, 200)
    assert np.abs(calibration(grid) - np.sqrt(grid)).max() < 0.03  # the true rate, between the bins' means


def test_calibration_is_monotone_keeps_nan_and_stays_a_probability():
    raw, right = _under_confident(5_000, 2)
    for calibration in (fit_calibration(raw, right), LABEL_CALIBRATION):
        p = calibration(np.r_[np.linspace(0.0, 1.0, 1001), np.nan])
        assert np.all(np.diff(p[:-1]) >= 0) and np.isnan(p[-1])
        assert np.all((p[:-1] >= 0) & (p[:-1] <= 1))


def test_a_labeling_reports_its_windows_confidences_calibrated_and_its_first_frame_sure():
    labeling = CaptureLabeling(generated_capture(frames=40, seed=3), LabelingOptions(window=10))
    outcomes = list(labeling.windows())
    result = labeling.result(outcomes)
    raw = labeling.result(outcomes, calibrated=False).confidence
    assert not np.allclose(result.confidence[1:], raw[1:], equal_nan=True)  # the map changes what is reported
    assert np.allclose(result.confidence[1:], LABEL_CALIBRATION(raw[1:]), equal_nan=True)
    assert np.all(result.confidence[0] == 1.0)
    # the windows count their raw doubt; the result flags the same labels, calibrated
    occluded = np.concatenate([o.point_index < 0 for o in outcomes])
    counted = sum(o.stats.doubtful for o in outcomes)
    assert counted == int(reported_doubtful(result.confidence[1:], occluded).sum()) == int(
        doubtful_labels(raw[1:], occluded).sum())


def test_the_reported_threshold_flags_exactly_the_labels_the_raw_one_does():
    raw = np.linspace(0.0, 1.0, 200_001)
    assert np.array_equal(LABEL_CALIBRATION(raw) < REPORTED_DOUBTFUL_BELOW, raw < DOUBTFUL_BELOW)
