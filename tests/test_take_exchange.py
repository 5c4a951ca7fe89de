"""Two markers exchanged for most of a take, given back on the say of the labeled first frame:
the traced Hamner case (a wrist pair 63 mm apart, 12 mm apart in their distance to the elbow,
their only rigid neighbour) with skin motion that moves both distances alike."""

import json
from pathlib import Path

import numpy as np
import pytest
from rigid_scenes import SwingingSegment
from service_fixtures import document_json, generated_capture
from typer.testing import CliRunner

import formulations.markers.take_exchange as take_exchange
import service.labeling.exchanged as exchanged_module
from formulations.markers.state import MarkerState
from formulations.markers.take_exchange import TakeExchange, best_run, take_exchanges
from service.cli.app import app
from service.io.recording import LabeledTrajectories
from service.labeling.exchanged import EXCHANGED_CONFIDENCE, exchange_summary, exchanged_back

# Hamner's right forearm: the elbow (0), radial (1) and ulnar (2) wrist markers, 271 and
# 259 mm from the elbow; an upper-arm marker (3) swinging about the elbow; a trunk marker (4).
FOREARM = np.array([[0, 0, 0], [268, 40, 0], [258, -23, 0]], float)
LAT, MED = 1, 2
RUN = SwingingSegment(turn=(0.8, 0.3, 1.2), periods=(9, 13, 7), speed=5.0, sway=60.0, hinge=0, swing=0.9, swing_period=6)
FRAMES, EXCHANGED_AT = 400, 83


def _take(noise: float = 2.0, slide_mm: float = 8.0, seed: int = 0, settled_mm: float = 0.0) -> np.ndarray:
    """``(FRAMES, 5, 3)``: the elbow's skin slides along the forearm by ``slide_mm``, which
    moves both wrist distances alike (as a pose the first frame did not have does), and after
    the first frame stays ``settled_mm`` further along."""
    rng = np.random.default_rng(seed)
    frames = []
    for t in range(FRAMES):
        forearm = FOREARM.copy()
        forearm[0, 0] += slide_mm * np.sin(t / 17) + (settled_mm if t else 0.0)
        frames.append(RUN.frame(t, forearm))
    return np.stack(frames) + rng.normal(0, noise, (FRAMES, 5, 3))


def _exchanged(take: np.ndarray, start: int = EXCHANGED_AT) -> np.ndarray:
    labeled = take.copy()
    labeled[start:, [LAT, MED]] = take[start:, [MED, LAT]]
    return labeled


def _found(labeled: np.ndarray) -> list[tuple[int, int, int, int]]:
    neighbours = MarkerState.from_first_frame(labeled[0], n_neighbours=4).neighbours
    return [(e.a, e.b, e.start, e.stop) for e in take_exchanges(labeled, labeled[0], neighbours)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_exchange_kept_to_the_end_is_given_back_from_where_it_began(seed: int) -> None:
    (found,) = _found(_exchanged(_take(seed=seed)))
    a, b, start, stop = found
    assert (a, b) == (LAT, MED)
    assert abs(start - EXCHANGED_AT) <= 2
    assert stop == FRAMES


def test_each_marker_distance_alone_would_take_the_skin_slide_for_an_exchange() -> None:
    """Why the pair is judged by the difference of its distances: with the slide, the radial
    marker's own distance to the elbow is nearer the ulnar one's first-frame distance in many
    frames where the labels are right."""
    take = _take(noise=0.0)
    d0 = np.linalg.norm(take[0, [LAT, MED]] - take[0, 0], axis=1)
    lateral = np.linalg.norm(take[:, LAT] - take[:, 0], axis=1)
    assert np.mean(np.abs(lateral - d0[1]) < np.abs(lateral - d0[0])) > 0.2


def test_a_first_frame_in_a_pose_the_take_leaves_still_judges_the_pair() -> None:
    """Both distances 15 mm off the first frame's for the rest of the take: each alone fits
    it badly, right or exchanged; their difference keeps it."""
    take = _take(slide_mm=2.0, settled_mm=15.0)
    assert _found(take) == []
    ((a, b, start, stop),) = _found(_exchanged(take))
    assert (a, b, stop) == (LAT, MED, FRAMES) and abs(start - EXCHANGED_AT) <= 2


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_right_labels_are_left_alone(seed: int) -> None:
    assert _found(_take(noise=2.0, seed=seed)) == []


def test_the_labeled_first_frame_is_never_exchanged() -> None:
    assert _found(_exchanged(_take(), start=0)) in ([], [(LAT, MED, 1, FRAMES)])


def test_best_run_is_the_largest_sum_of_any_run_that_may_start_and_stop_there() -> None:
    rng = np.random.default_rng(3)
    for _ in range(300):
        frames = int(rng.integers(2, 30))
        gain, may = rng.normal(-0.2, 1.0, frames), rng.random(frames + 1) < 0.4
        start, stop, total = best_run(gain, may)
        runs = [(gain[s:e].sum(), s, e) for s in range(1, frames) for e in range(s + 1, frames + 1)
                if may[s] and (may[e] or e == frames)]
        if not runs:
            assert total == -np.inf
            continue
        assert total == pytest.approx(max(runs)[0])
        assert 1 <= start < stop <= frames and may[start] and (may[stop] or stop == frames)
        assert gain[start:stop].sum() == pytest.approx(total)


def test_every_per_label_array_follows_the_exchange_and_its_labels_are_doubtful() -> None:
    take = _exchanged(_take())
    index = np.tile(np.arange(5), (FRAMES, 1))
    index[EXCHANGED_AT:, [LAT, MED]] = index[EXCHANGED_AT:, [MED, LAT]]
    labels = LabeledTrajectories(
        names=["elbow", "lat", "med", "arm", "trunk"], positions=take, occluded=np.zeros((FRAMES, 5), bool), rate=100.0,
        point_index=index, filled=np.full(take.shape, np.nan), confidence=np.ones((FRAMES, 5)),
    )
    back, exchanges = exchanged_back(labels, MarkerState.from_first_frame(take[0], n_neighbours=4))
    assert exchange_summary(exchanges, labels.names) == [{"markers": ["lat", "med"], "frames": [EXCHANGED_AT, FRAMES]}]
    assert (back.point_index == np.arange(5)).all()
    assert np.allclose(back.positions, _take())
    assert (back.confidence[EXCHANGED_AT + 2 :, [LAT, MED]] == EXCHANGED_CONFIDENCE).all()
    assert (back.confidence[:, [0, 3, 4]] == 1.0).all()


def test_track_says_which_pairs_the_first_frame_gave_back(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The summary reports the exchanges the repair made (here one is forced on a generated
    take, so that the report, not the repair, is what is checked) and its labels are doubtful."""
    source, capture = tmp_path / "take.json", generated_capture(60)
    source.write_text(document_json(capture))
    forced = [TakeExchange(0, 1, 10, 30, 99.0)]
    monkeypatch.setattr(exchanged_module, "take_exchanges", lambda *args: forced)
    monkeypatch.setattr(exchanged_module, "take_mirrors", lambda *args: [])  # it would give the forced exchange back
    done = CliRunner().invoke(app, ["track", str(source), "--out", str(tmp_path / "a.csv"), "--json", "--one-pass"])
    assert done.exit_code == 0, done.output
    summary = json.loads(done.stdout.splitlines()[-1])
    assert summary["exchanged_back"] == [{"markers": capture.names[:2], "frames": [10, 30]}]
    assert summary["doubtful_fraction"] >= 30 / (60 * len(capture.names))
    line = CliRunner().invoke(app, ["track", str(source), "--out", str(tmp_path / "b.csv"), "--one-pass"], env={"COLUMNS": "400"})
    assert "1 exchanged pair given back by the first frame's shape (labels doubtful)" in line.stdout


# A foot: heel (0) and fifth metatarsal (1) exchanged, judged by the ankle (2) and the toe (3),
# the toe on a foreign point (100 mm off the foot, as CMU 135_02's file holds it) over most of
# the exchanged run.
FOOT = np.array([[0, 0, 0], [165, 40, 0], [20, 30, 75], [230, 10, 10]], float)
FOOT_FRAMES, FOOT_EXCHANGED, TOE_OFF = 1200, 1100, slice(1100, 1160)  # wrong labels under a tenth: the pairs stay rigid


def _foot_take(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    take = np.stack([RUN.frame(t, FOOT) for t in range(FOOT_FRAMES)]) + rng.normal(0, 1.0, (FOOT_FRAMES, 6, 3))
    take[FOOT_EXCHANGED:, [0, 1]] = take[FOOT_EXCHANGED:, [1, 0]]
    take[TOE_OFF, 3] += [0.0, 0.0, 100.0]
    return take


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_witness_on_a_foreign_point_neither_judges_nor_spoils_the_fit(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The toe's terms are beyond CAP both ways where it sits off the foot: the gain caps them
    to nothing, and the fit leaves them out. Counted, they fail the exchanged labels' fit."""
    take = _foot_take(seed)
    ((a, b, start, stop),) = _found(take)
    assert (a, b, stop) == (0, 1, FOOT_FRAMES) and abs(start - FOOT_EXCHANGED) <= 2
    monkeypatch.setattr(take_exchange, "_judging", lambda apart, apart0, sd: np.ones(apart.shape, bool))
    assert _found(take) == []


def test_a_run_no_witness_judges_is_not_given_back(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every witness term beyond CAP both ways (as where the witnesses are themselves on each
    other's points): the fit of nothing would pass, so the run is refused for want of a judge;
    without that bar the same gain is taken."""
    take = _foot_take(0)
    monkeypatch.setattr(take_exchange, "_judging", lambda apart, apart0, sd: np.zeros(apart.shape, bool))
    assert _found(take) == []
    monkeypatch.setattr(take_exchange, "JUDGED_SHARE", 0.0)
    assert [found[:2] for found in _found(take)] == [(0, 1)]
