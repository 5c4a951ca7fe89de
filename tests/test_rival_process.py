"""The frame-by-frame and ``mht`` readings run in child processes beside the second pass
(``service.labeling.rival_process``): the same labels as read here, its failures said, a stop ends it."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from service_fixtures import generated_capture

import service.labeling.capture_labeling as capture_labeling
import service.labeling.rival_process as rival_process
from formulations.markers.state import MarkerState
from service.capture.capture import Capture, LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.rival_process import EarlyStart, RivalBeside


def _doubtful() -> Capture:
    """A take doubtful enough for a second pass and the frame-by-frame reading."""
    return generated_capture(frames=120, seed=1, noise_mm=3.0, ghosts_per_frame=6.0)


def _spied(monkeypatch: pytest.MonkeyPatch) -> list[RivalBeside]:
    """The children started from now on (by ``refine`` or ``EarlyStart``)."""
    started: list[RivalBeside] = []

    class Spied(RivalBeside):
        def __init__(self, capture: Capture, options: LabelingOptions, reading: str = "frame-by-frame") -> None:
            super().__init__(capture, options, reading)
            started.append(self)

    monkeypatch.setattr(rival_process, "RivalBeside", Spied)
    return started


def _labeled(monkeypatch: pytest.MonkeyPatch, late: bool, early: bool, mht: bool = False,
             ) -> tuple[CaptureLabeling, object, list[RivalBeside]]:
    """``late``: ``refine`` starts the children; ``early``: the first pass does (``EarlyStart``);
    ``mht``: the ``mht`` reading runs too."""
    started = _spied(monkeypatch)
    monkeypatch.setattr(capture_labeling, "runs_beside", lambda seconds, readings: late)
    monkeypatch.setattr(rival_process, "runs_beside", lambda seconds, readings: early)
    labeling = CaptureLabeling(_doubtful(), LabelingOptions(window=10, mht_reading=mht))
    progress: list[tuple[int, int]] = []
    result, _ = labeling.label(progress=lambda k, n: progress.append((k, n)))
    passes = 6 if mht else 4  # the windows' two passes, and each reading's two
    assert progress[-1] == (passes * labeling.n_windows, passes * labeling.n_windows)
    return labeling, result, started


@pytest.fixture(scope="module")
def read_here() -> dict[bool, tuple[CaptureLabeling, object]]:
    """The doubtful take labeled with the readings in this process, without and with ``mht``'s."""
    labeled = {}
    with pytest.MonkeyPatch.context() as monkeypatch:
        for mht in (False, True):
            here, here_result, none = _labeled(monkeypatch, late=False, early=False, mht=mht)
            assert here.rival is not None and not none  # the take is doubtful: the readings ran, here
            assert (here.hypotheses is not None) == mht
            labeled[mht] = here, here_result
    return labeled


@pytest.mark.parametrize("late, early, mht", [(True, False, False), (False, True, False), (False, True, True)])
def test_the_reading_beside_gives_the_labels_read_here(
    monkeypatch: pytest.MonkeyPatch, read_here: dict[bool, tuple[CaptureLabeling, object]], late: bool, early: bool,
    mht: bool,
) -> None:
    here, here_result = read_here[mht]
    beside, beside_result, started = _labeled(monkeypatch, late, early, mht)
    assert [child.reading for child in started] == ["frame-by-frame", "mht"][: 1 + mht]  # ... the second time in children
    assert all(child.ended for child in started)
    assert beside.rival == here.rival and beside.choice == here.choice and beside.hypotheses == here.hypotheses
    for field in ("positions", "point_index", "confidence", "filled"):
        assert np.array_equal(getattr(beside_result, field), getattr(here_result, field), equal_nan=True), field


def test_a_reading_started_early_is_ended_when_the_take_is_not_doubtful(monkeypatch: pytest.MonkeyPatch) -> None:
    started = _spied(monkeypatch)
    monkeypatch.setattr(rival_process, "runs_beside", lambda seconds, readings: True)
    early = EarlyStart(_doubtful(), LabelingOptions(window=10))
    first_pass = CaptureLabeling(_doubtful(), LabelingOptions(window=10, rival_reading=False)).windows()  # no child of its own
    list(early.watched(first_pass))
    assert len(started) == 1 and not started[0].ended  # doubtful: started while the first pass ran
    assert early.taken(False).children == {}
    assert started[0].ended


def test_the_first_pass_is_judged_long_enough_from_its_windows_so_far(monkeypatch: pytest.MonkeyPatch) -> None:
    """A reading beside starts once the first pass looks long, not once it has taken long."""
    asked: list[float] = []
    monkeypatch.setattr(rival_process, "runs_beside", lambda seconds, readings: asked.append(seconds) and False)
    windows = list(CaptureLabeling(_doubtful(), LabelingOptions(window=10, rival_reading=False)).windows())
    list(EarlyStart(_doubtful(), LabelingOptions(window=10), windows=len(windows)).watched(iter(windows)))
    spent = np.cumsum([w.stats.total_seconds for w in windows])
    assert np.allclose(asked, spent / np.arange(1, len(windows) + 1) * len(windows))
    assert asked[0] > spent[0]  # after one window of several, the whole pass is projected


def test_a_marker_state_travels_to_another_process_whole() -> None:
    """Its weakly held advances stay behind; what it predicts and how it advances do not change."""
    state = MarkerState.from_first_frame(np.random.default_rng(0).uniform(0, 500, (12, 3)))
    state = state.advance(state.position + 3.0, np.ones(12, bool)).advance(state.position + 7.0, np.arange(12) % 3 > 0)
    copy = pickle.loads(pickle.dumps(state))
    assert np.array_equal(copy.predict(), state.predict())
    seen = np.arange(12) % 4 > 0
    assert np.array_equal(copy.advance(state.position + 9.0, seen).position, state.advance(state.position + 9.0, seen).position)


def test_a_child_that_fails_says_why() -> None:
    """Options the child cannot label with (no second pass: no frame-by-frame reading to run)."""
    failed = r"frame-by-frame reading's process failed \(exit 1\): AssertionError"
    with RivalBeside(generated_capture(frames=20), LabelingOptions(second_pass=False)) as child, \
            pytest.raises(RuntimeError, match=failed):
        child.read()


def test_a_stop_ends_the_child() -> None:
    with RivalBeside(_doubtful(), LabelingOptions(window=10)) as child:
        assert child.read(stop=lambda: True) is None
    assert child.ended


def test_with_the_mht_reading_the_readings_go_beside_from_a_smaller_take(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(rival_process.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    bar = rival_process.BESIDE_MIN_SECONDS
    assert not rival_process.runs_beside(0.6 * bar) and rival_process.runs_beside(bar)
    assert rival_process.runs_beside(0.6 * bar, readings=2)  # two readings' passes to take off this process
    monkeypatch.setattr(rival_process.os, "sched_getaffinity", lambda pid: {0}, raising=False)
    assert not rival_process.runs_beside(10 * bar, readings=2)  # one core: nothing to run beside on
