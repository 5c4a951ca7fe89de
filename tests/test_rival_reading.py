"""A doubtful take read frame by frame as well, the marker groups that reading labels better
taken from it (``service.labeling.rival_reading``)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import DATA
from service_fixtures import generated_capture

import service.labeling.capture_labeling as capture_labeling_module
import service.labeling.exchanged as exchanged_module
import service.labeling.rival_reading as rival_module
import service.labeling.second_pass as second_pass_module
from service.capture.capture import LabelingOptions
from service.capture.from_recording import capture_from_span
from service.errors import InputError
from service.io.formats import read_labeled
from service.io.recording import LabeledTrajectories
from service.labeling.capture_labeling import CaptureLabeling

WALK = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "135_02.c3d"
START = 4400  # the file's own left foot is corrupt at 4483-4600 (a repeated frame, then LMT5-LTOE 94 -> 183 mm)
FOOT = ["male:LHEE", "male:LANK", "male:LMT5"]


def _foot_right_at_the_end(names: list[str], positions: np.ndarray) -> float:
    """Share of the left foot's samples in the take's last 300 frames labeled with their own point."""
    truth = read_labeled(WALK).without_unlabeled()
    own = truth.positions[-300:][:, [truth.names.index(n) for n in FOOT]]
    given = positions[-300:][:, [names.index(n) for n in FOOT]]
    present = np.isfinite(own).all(axis=2)
    same = np.linalg.norm(np.nan_to_num(given - own, nan=1e9), axis=2) < 1e-3
    return float((same & present).sum() / present.sum())


def _labeled(monkeypatch: pytest.MonkeyPatch, rival: bool, rotations: bool) -> tuple[CaptureLabeling, LabeledTrajectories]:
    """The walk from ``START`` labeled; ``rotations`` False turns the take-wide rotation repair
    off (``take_rotation``), which since it landed gives the foot back by itself."""
    if not rotations:
        monkeypatch.setattr(exchanged_module, "take_rotations", lambda *args: [])
    capture, _ = capture_from_span(read_labeled(WALK), START)
    labeling = CaptureLabeling(capture, LabelingOptions(rival_reading=rival))
    result, _ = labeling.label()
    return labeling, result


def test_the_window_reading_alone_keeps_the_foot_round_to_the_end_without_the_rotation_repair(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Without the rival and the rotation repair: after the corrupt stretch the window reading
    passes the foot's labels round and keeps them so for 700 frames (the setup both are for)."""
    labeling, result = _labeled(monkeypatch, rival=False, rotations=False)
    assert labeling.choice is not None and labeling.choice.second_doubtful is not None  # doubtful: a second pass ran
    assert labeling.rival is None
    assert _foot_right_at_the_end(result.names, result.positions) < 0.1


def test_the_rotation_repair_gives_the_foot_back(monkeypatch: pytest.MonkeyPatch) -> None:
    labeling, result = _labeled(monkeypatch, rival=False, rotations=True)
    assert _foot_right_at_the_end(result.names, result.positions) > 0.9
    assert any(len(e.markers) == 3 for e in labeling.exchanges)


def test_the_frame_by_frame_reading_gives_the_foot_back(monkeypatch: pytest.MonkeyPatch) -> None:
    labeling, result = _labeled(monkeypatch, rival=True, rotations=False)
    assert labeling.rival is not None
    assert labeling.rival.markers >= 1 and labeling.rival.rival_off_mm < labeling.rival.window_off_mm  # type: ignore[operator]
    assert _foot_right_at_the_end(result.names, result.positions) > 0.9


def test_a_take_not_doubtful_is_read_once() -> None:
    """A clean take runs no second pass, so no frame-by-frame reading either: one pass's time."""
    capture, _ = capture_from_span(read_labeled(WALK), 0, 300)
    labeling = CaptureLabeling(capture)
    labeling.label()
    assert labeling.choice is not None and labeling.choice.second_doubtful is None
    assert labeling.rival is None


def test_the_rival_reading_is_an_option_that_must_be_a_bool() -> None:
    with pytest.raises(InputError, match="rival_reading must be True or False"):
        LabelingOptions(rival_reading="yes")  # type: ignore[arg-type]


def test_a_stop_during_the_frame_by_frame_reading_abandons_it(monkeypatch) -> None:
    """A job cancelled while the frame-by-frame reading runs stops there, as in the second pass."""
    monkeypatch.setattr(second_pass_module, "doubtful_share", lambda outcomes: 0.5)  # doubtful: both run
    labeling = CaptureLabeling(generated_capture(frames=40, seed=3), LabelingOptions(window=10))
    outcomes = list(labeling.windows())
    asked: list[int] = []

    def stop() -> bool:
        asked.append(1)
        return len(asked) > labeling.n_windows  # the second pass runs whole, the reading is stopped

    assert labeling.refine(outcomes, stop=stop) is None
    assert len(asked) == labeling.n_windows + 1
    assert labeling.rival is None


def test_the_merges_judge_the_labels_they_merge_and_the_second_pass_learns_from_the_repaired(monkeypatch) -> None:
    """Both merges take window columns, so they must group and judge the windows' own labels.
    Judged on the take-wide repairs' labels, the groups were those of other point indices: on the
    real wheelchair racing take the window reading had the right glove, its repaired labels gave
    GloveR2 and GloveR3 one point for 568 frames, and the merge then took an exchanged glove
    (refine stage 97.77 -> 95.08 %). Here a repair that marks marker 0 must not reach a judge;
    the spreads the second pass starts from are still learned from the repaired labels."""
    def marked(labels: LabeledTrajectories, first: object) -> tuple[LabeledTrajectories, list]:
        labels.point_index = labels.point_index.copy()
        labels.point_index[:, 0] = 10**6
        labels.positions = labels.positions.copy()
        labels.positions[:, 0] += 1000.0
        return labels, []

    judged: list[tuple[np.ndarray, np.ndarray]] = []
    real = second_pass_module.labels_taken

    def spy(points, capped, judged_triples, **kwargs):
        judged.append(points)
        return real(points, capped, judged_triples, **kwargs)

    learned: list[np.ndarray] = []
    real_spread = second_pass_module.with_take_spread

    def spread_spy(first, positions):
        learned.append(positions)
        return real_spread(first, positions)

    monkeypatch.setattr(second_pass_module, "with_take_spread", spread_spy)
    monkeypatch.setattr(capture_labeling_module, "exchanged_back", marked)
    monkeypatch.setattr(second_pass_module, "doubtful_share", lambda outcomes: 0.5)  # doubtful: both run
    for module in (second_pass_module, rival_module):
        monkeypatch.setattr(module, "labels_taken", spy)
    labeling = CaptureLabeling(generated_capture(frames=40, seed=3), LabelingOptions(window=10))
    outcomes = list(labeling.windows())
    kept = labeling.refine(outcomes)
    assert kept is not None and labeling.rival is not None
    unrepaired = labeling.assembled(outcomes, repaired=False).positions[:, 0]
    assert np.allclose(learned[0][:, 0], unrepaired + 1000.0, equal_nan=True)
    assert len(judged) >= 2  # the second pass's merge and the frame-by-frame one
    assert all((points < 10**6).all() for pair in judged for points in pair)
    assert labeling.assembled(kept).point_index[:, 0].max() == 10**6  # the repair does run on what is kept
