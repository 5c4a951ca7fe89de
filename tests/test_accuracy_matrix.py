"""The accuracy matrix of issue 11: its split, its takes, a fast slice of cells, its goals."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import DATA
from test_scores import MARKER_FRAMES, PERFECT, _capture, _labeled

from service.evaluation.matrix import HALVES, RECORDINGS, Cell, CellKey, prepare, recording_named, run_cell
from service.evaluation.matrix_summary import accuracy_goal, aggregate, goals
from service.evaluation.scores import block_counts

needs_data = pytest.mark.skipif(not DATA.exists(), reason="shared data absent")


def test_the_halves_are_disjoint_and_each_mixes_labs() -> None:
    names = [r.name for r in RECORDINGS]
    assert len(set(names)) == len(names) >= 10
    halves = {h: {r.name for r in RECORDINGS if r.half == h} for h in HALVES}
    assert set(halves["tuning"]) | set(halves["validation"]) == set(names)
    assert halves["tuning"] and halves["validation"] and not halves["tuning"] & halves["validation"]
    for half in HALVES:
        assert len({r.lab for r in RECORDINGS if r.half == half}) >= 5
    # Two takes of one lab go to opposite halves, so tuning cannot fit a lab.
    assert recording_named("cmu-85_02").half == "tuning"
    assert recording_named("cmu-135_02").half == "validation"


@pytest.mark.parametrize(("block_frames", "expected"), [
    # Frame 0 is unscored; frames 1..5 hold 3, 3, 3, 3, 2 markers, and frame 4's marker 0 is wrong.
    (2, [(3, 3), (6, 6), (5, 4)]),
    (4, [(9, 9), (5, 4)]),  # the 2-frame tail is half a block: it stays
    (5, [(MARKER_FRAMES, MARKER_FRAMES - 1)]),  # the 1-frame tail joins the block before
    (100, [(MARKER_FRAMES, MARKER_FRAMES - 1)]),
])
def test_block_counts_split_the_scored_marker_frames(block_frames: int, expected: list[tuple[int, int]]) -> None:
    point_index = PERFECT.copy()
    point_index[4, 0] = -1
    assert block_counts(_capture(), _labeled(point_index), block_frames) == expected


@needs_data
def test_every_recording_is_in_the_shared_data() -> None:
    assert [r.name for r in RECORDINGS if not (DATA / r.path).is_file()] == []


@needs_data
def test_a_take_without_a_complete_frame_drops_the_markers_absent_at_its_start() -> None:
    take = prepare(recording_named("ktk-racing"))
    # Frame 17 is the first with 40 of 46 markers; the six probes are never seen.
    assert take.start == 17
    assert take.dropped == tuple(f"Probe{i}" for i in range(1, 7))
    assert take.truth.n_markers == 40 and not take.truth.missing()[take.start].any()
    assert take.frames == 700 - 17 and take.own_gaps > 0


@needs_data
def test_a_frame_step_keeps_the_start_frame_and_every_kth_frame_at_a_kth_of_the_rate() -> None:
    full, step = prepare(recording_named("ktk-racing")), prepare(recording_named("ktk-racing"), frame_step=3)
    # the start (frame 17) stays a kept frame, its markers the same; frames before it keep the step
    assert step.truth.rate == full.truth.rate / 3 and step.truth.names == full.truth.names
    assert np.array_equal(step.truth.positions[step.start], full.truth.positions[full.start], equal_nan=True)
    assert np.array_equal(step.truth.positions, full.truth.positions[17 % 3 :: 3], equal_nan=True)
    assert step.frames == len(range(17, 700, 3))


@needs_data
def test_columns_that_copy_another_marker_are_left_out() -> None:
    take = prepare(recording_named("hdm05-mm"))
    assert take.truth.n_markers == 41 and take.start == 0 and take.dropped == ()
    assert not {"*0", "*1", "*2"} & set(take.truth.names)


@needs_data
def test_clean_condition_on_a_clean_take_labels_both_formulations_and_blocks_add_up() -> None:
    formulations = ("lp-l1", "nn-hungarian")
    cells = [run_cell(CellKey("cmu-85_02", "clean", 0, f), frames_cap=300, block_frames=100) for f in formulations]
    for cell in cells:
        assert (cell.frames, cell.markers, cell.half) == (300, 41, "tuning")
        assert cell.accuracy >= 0.99
        # No deletions: every marker is scored in frames 1..299.
        assert cell.marker_frames == 299 * 41
        assert len(cell.blocks) == 3
        assert sum(seen for seen, _ in cell.blocks) == cell.marker_frames
        assert sum(correct for _, correct in cell.blocks) == cell.correct
    assert [r.formulation for r in aggregate(cells)] == list(formulations)


def _cell(recording: str, condition: str, seed: int, formulation: str, *, swaps: int,
          blocks: tuple[tuple[int, int], ...]) -> Cell:
    seen, correct = sum(b[0] for b in blocks), sum(b[1] for b in blocks)
    return Cell(CellKey(recording, condition, seed, formulation), recording_named(recording).half,
                1000 * len(blocks), 41, correct / seen, swaps, 0, 0, seen, correct, 0.001, blocks)


def test_aggregate_pools_counts_over_seeds() -> None:
    cells = [_cell("cmu-85_02", "default", 0, "lp-l1", swaps=2, blocks=((100, 90), (100, 100))),
             _cell("cmu-85_02", "default", 1, "lp-l1", swaps=3, blocks=((300, 300), (100, 100)))]
    (row,) = aggregate(cells)
    # Pooled, not the mean of 0.95 and 1.0.
    assert row.accuracy == pytest.approx(590 / 600)
    assert row.block_accuracy == pytest.approx((390 / 400, 1.0))
    assert (row.swaps, row.seeds, row.frames) == (5, 2, 2000)


def test_accuracy_floor_follows_the_noise() -> None:
    assert [accuracy_goal(n) for n in (0.5, 2.0, 3.0, 4.0)] == [0.995, 0.995, None, 0.97]


def test_goals_fail_a_validation_row_below_floor_with_more_swaps_and_drift() -> None:
    drifting = ((1000, 980), (1000, 970), (1000, 960), (1000, 950))  # 96.5 %, 3 points down
    steady = ((1000, 940),) * 4
    cells = [_cell("cmu-135_02", "noise-4", 0, "lp-l1", swaps=5, blocks=drifting),
             _cell("cmu-135_02", "noise-4", 0, "nn-hungarian", swaps=3, blocks=steady),
             # Tuning rows are never checked, however bad.
             _cell("cmu-85_02", "noise-4", 0, "lp-l1", swaps=9, blocks=((1000, 10),))]
    checks = {c.goal: c for c in goals(aggregate(cells))}
    assert set(checks) == {"beats-baseline", "accuracy", "drift"}
    assert not any(c.passed for c in checks.values())
    assert all(c.recording == "cmu-135_02" and c.formulation == "lp-l1" for c in checks.values())


def test_goals_pass_a_steady_row_above_its_floor() -> None:
    cells = [_cell("cmu-135_02", "default", 0, "lp-l1", swaps=0, blocks=((1000, 998),) * 4),
             _cell("cmu-135_02", "default", 0, "nn-hungarian", swaps=1, blocks=((1000, 990),) * 4)]
    assert [(c.goal, c.passed) for c in goals(aggregate(cells))] == [
        ("beats-baseline", True), ("accuracy", True), ("drift", True)]


def test_a_row_whose_file_labels_jump_is_also_judged_without_them() -> None:
    # 30 of 1,000 marker-frames lie where the file's own label jumped; the labeling got none of them
    cell = replace(_cell("ktk-basket", "default", 0, "lp-l1", swaps=0, blocks=((1000, 970),)),
                   file_jumps=30, correct_on_jumps=0)
    (row,) = aggregate([cell])
    assert row.known_accuracy == pytest.approx(970 / 970)
    checks = {c.goal: c.passed for c in goals([row])}
    assert checks == {"accuracy": False, "accuracy-known": True}
