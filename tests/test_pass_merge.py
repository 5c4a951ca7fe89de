"""Two passes merged group by group and run by run: each group of markers they label
differently takes, over each stretch where they disagree on it, the labels of the pass that
bends its rigid pairs less off the first frame."""

from __future__ import annotations

import numpy as np
import pytest

from formulations.markers.first_frame_shape import first_frame_disagreement, pair_offsets
from formulations.markers.pass_merge import labels_taken
from formulations.markers.state import MarkerState

FRAMES = 60


def _two_plates(seed: int = 0) -> np.ndarray:
    """``(F, 8, 3)`` two rigid plates of four markers each (2 m apart), each turning its own way."""
    rng = np.random.default_rng(seed)
    plates = []
    for offset in (0.0, 2000.0):
        body = rng.normal(0.0, 60.0, (4, 3))
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        frames = []
        for f in range(FRAMES):
            angle = 0.04 * f
            k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            turn = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
            frames.append(body @ turn.T + [offset + 3.0 * f, 0.0, 0.0])
        plates.append(np.stack(frames))
    return np.concatenate(plates, axis=1)


def _labeling(truth: np.ndarray, swapped: tuple[int, int], after: int) -> tuple[np.ndarray, np.ndarray]:
    """Point indices (point i of each frame is marker i's) and positions, ``swapped`` exchanged from ``after``."""
    points = np.tile(np.arange(truth.shape[1]), (len(truth), 1))
    a, b = swapped
    points[after:, [a, b]] = points[after:, [b, a]]
    return points, truth[np.arange(len(truth))[:, None], points]


def _taken(truth: np.ndarray, one: np.ndarray, two: np.ndarray) -> np.ndarray:
    """``labels_taken`` for two passes' point indices (point i of each frame is marker i's)."""
    neighbours = MarkerState.from_first_frame(truth[0], n_neighbours=7).neighbours
    positions = [truth[np.arange(FRAMES)[:, None], p] for p in (one, two)]
    return labels_taken((one, two), *pair_offsets(positions, truth[0], neighbours))


def test_each_pass_keeps_the_plate_it_labels_right() -> None:
    """Pass one exchanges two markers of the second plate, pass two two of the first: neither
    pass is right whole, and the merge takes each plate from the pass that has it right."""
    truth = _two_plates()
    neighbours = MarkerState.from_first_frame(truth[0], n_neighbours=7).neighbours
    one, two = _labeling(truth, (5, 6), 20), _labeling(truth, (0, 1), 30)
    whole = first_frame_disagreement([one[1], two[1]], truth[0], neighbours)
    kept = int(np.argmin(whole))
    assert not np.array_equal((one, two)[kept][0], np.tile(np.arange(8), (FRAMES, 1)))  # a whole pass keeps an exchange
    take = labels_taken((one[0], two[0]), *pair_offsets([one[1], two[1]], truth[0], neighbours))
    assert take.any(axis=0).tolist() == [0, 0, 0, 0, 0, 1, 1, 0]  # only the markers the passes label differently move
    merged = np.where(take, two[0], one[0])
    assert np.array_equal(merged, np.tile(np.arange(8), (FRAMES, 1)))


def test_one_group_right_in_each_pass_in_turn() -> None:
    """Both passes exchange the same two markers, the first early and the second late: taking
    either pass's labels for the pair over the whole take keeps one exchange; judged stretch by
    stretch, the pair is right in every frame."""
    right = np.tile(np.arange(8), (FRAMES, 1))
    one, two = right.copy(), right.copy()
    one[10:25, [0, 1]] = one[10:25, [1, 0]]
    two[40:55, [0, 1]] = two[40:55, [1, 0]]
    assert not np.array_equal(one, right) and not np.array_equal(two, right)  # the group whole: an exchange either way
    take = _taken(_two_plates(1), one, two)
    assert np.array_equal(np.where(take, two, one), right)
    assert take[:, 2:].sum() == 0 and take[:10].sum() == 0  # nothing moves where the passes agree


@pytest.mark.parametrize("seed", range(8))
def test_no_frame_gives_one_point_to_two_markers(seed: int) -> None:
    """Whatever the judge picks per group, a point taken by different markers in the two passes
    puts them in one group, so the merge never labels one point twice."""
    rng = np.random.default_rng(seed)
    truth = _two_plates(seed) + rng.normal(0.0, 5.0, (FRAMES, 8, 3))
    neighbours = MarkerState.from_first_frame(truth[0], n_neighbours=7).neighbours
    passes = []
    for _ in range(2):
        points = np.tile(np.arange(10), (FRAMES, 1))[:, :8].copy()  # points 8, 9: spare points nobody holds
        for _ in range(6):
            a, b = rng.choice(8, 2, replace=False)
            start, stop = sorted(rng.choice(FRAMES, 2, replace=False))
            points[start:stop, [a, b]] = points[start:stop, [b, a]]
        points[rng.random(points.shape) < 0.05] = -1
        free = rng.random(points.shape) < 0.02
        points[free] = rng.choice([8, 9], int(free.sum()))
        passes.append(points)
    for p in passes:  # a pass itself labels each point at most once per frame
        for row in p:
            held = row[row >= 0]
            again = np.ones(len(held), bool)
            again[np.unique(held, return_index=True)[1]] = False
            row[np.flatnonzero(row >= 0)[again]] = -1
    clouds = np.concatenate([truth, truth[:, :2] + 300.0], axis=1)
    positions = [np.where((p >= 0)[..., None], clouds[np.arange(FRAMES)[:, None], np.maximum(p, 0)], np.nan) for p in passes]
    take = labels_taken((passes[0], passes[1]), *pair_offsets(positions, truth[0], neighbours))
    merged = np.where(take, passes[1], passes[0])
    for row in merged:
        held = row[row >= 0]
        assert len(held) == len(np.unique(held))


def test_a_reading_that_labels_nothing_is_not_taken() -> None:
    """A second reading with no label at all (every marker lost) leaves the first's labels;
    it once raised an IndexError looking for shared points."""
    truth = _two_plates(2)
    neighbours = MarkerState.from_first_frame(truth[0], n_neighbours=7).neighbours
    right = np.tile(np.arange(8), (FRAMES, 1))
    empty = np.full_like(right, -1)
    positions = [truth, np.full_like(truth, np.nan)]
    take = labels_taken((right, empty), *pair_offsets(positions, truth[0], neighbours))
    assert not take.any()


def test_two_disagreements_at_once_are_judged_apart() -> None:
    """Pass one exchanges two markers of the first plate while pass two exchanges two of the
    second, over the same frames; an earlier exchange across the plates in pass one alone puts
    all four in one group. Judged as one stretch, the two exchanges tie and one stays; as two
    events (labels that differ, joined by a point or by one marker's consecutive frames), each
    plate is right."""
    right = np.tile(np.arange(8), (FRAMES, 1))
    one, two = right.copy(), right.copy()
    one[5:9, [1, 5]] = one[5:9, [5, 1]]
    one[30:50, [0, 1]] = one[30:50, [1, 0]]
    two[30:50, [4, 5]] = two[30:50, [5, 4]]
    merged = np.where(_taken(_two_plates(3), one, two), two, one)
    assert np.array_equal(merged, right)
