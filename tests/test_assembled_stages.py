"""``CaptureLabeling.assembled``: the labels each stage of ``label`` hands on, which
``bench/real_stages.py`` scores: the windows' own, and with the take-wide repairs given back."""

import numpy as np
import pytest
from service_fixtures import generated_capture

import service.labeling.exchanged as exchanged_module
from formulations.markers.take_exchange import TakeExchange
from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling


def test_the_repaired_labels_differ_from_the_windows_by_the_repair_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    """An exchange forced over frames 10-30 (so the check is of the stages, not of the repair):
    the windows' labels keep their reading, the repaired ones swap exactly those frames, and
    the result's labels are the repaired ones."""
    monkeypatch.setattr(exchanged_module, "take_exchanges", lambda *args: [TakeExchange(0, 1, 10, 30, 99.0)])
    monkeypatch.setattr(exchanged_module, "take_mirrors", lambda *args: [])  # it would give the forced exchange back
    labeling = CaptureLabeling(generated_capture(60), LabelingOptions(second_pass=False))
    outcomes = list(labeling.windows())
    windows, repaired = labeling.assembled(outcomes, repaired=False), labeling.assembled(outcomes)
    assert labeling.exchanges == [TakeExchange(0, 1, 10, 30, 99.0)]
    swapped = windows.point_index.copy()
    swapped[10:30, [0, 1]] = swapped[10:30, [1, 0]]
    np.testing.assert_array_equal(repaired.point_index, swapped)
    assert not np.array_equal(windows.point_index, repaired.point_index)
    np.testing.assert_array_equal(labeling.result(outcomes).point_index, repaired.point_index)
