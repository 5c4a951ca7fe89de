"""Acceptance on a real recording: CMU 85_02 through the issue's scenario."""

import dataclasses

from conftest import DATA

from service.evaluation.cloud import evaluate
from service.evaluation.scenario import Scenario
from service.io.formats import read_labeled

CMU_85_02 = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"


def test_cmu_85_02_noisy_cloud_is_labeled_above_99_5_percent():
    truth = read_labeled(CMU_85_02)
    scenario = Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0, seed=0)
    result = evaluate(truth, scenario)
    summary = result.summary()
    assert summary["frames"] == 810 and summary["markers"] == 41
    assert summary["label_accuracy"] >= 0.995
    assert summary["ghost_recall"] >= 0.99
    assert summary["integral_window_fraction"] == 1.0


def test_clean_cloud_is_labeled_exactly():
    truth = read_labeled(CMU_85_02)
    scenario = Scenario(noise_mm=0.0, drop_rate=0.0, ghosts_per_frame=0.0, frames=300)
    result = evaluate(truth, dataclasses.replace(scenario, seed=1))
    assert result.scores.label_accuracy == 1.0
    assert result.scores.swaps == 0
