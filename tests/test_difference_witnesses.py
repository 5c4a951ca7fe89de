"""A pair that no marker is rigid with, exchanged for a stretch and given back by the
difference of its distances to the markers around it (``formulations.markers.difference_witnesses``):
the basket sprint's head, its temple and ear markers left alone on a bending neck."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import formulations.markers.take_exchange as take_exchange_module
from formulations.markers.difference_witnesses import CAP, difference_witnesses, fit_spread
from formulations.markers.state import MarkerState
from formulations.markers.take_exchange import rigid_pairs, take_exchanges

FRAMES = 400
TRUNK = np.array([[0, 0, 0], [150, 0, -40], [-150, 0, -40], [0, -60, -250], [100, -50, -300]], float)
NECK = np.array([0.0, 0.0, 60.0])  # the joint the head turns about, on the trunk
HEAD = np.array([[60, 80, 160], [-10, 60, 130]], float)  # temple and ear about the neck joint, 78 mm apart
TEMPLE, EAR = 5, 6
EXCHANGED = slice(150, 250)


def _take(seed: int, lean: float = 0.0) -> np.ndarray:
    """``(FRAMES, 7, 3)``: a trunk turning and walking, the head bending on it by up to 26
    degrees, and from frame 10 to 30 leaning ``lean`` radians to the side for good."""
    t = np.arange(FRAMES)
    trunk_turn = Rotation.from_rotvec(np.outer(np.sin(t / 40), [0, 0, 0.6])).as_matrix()
    bend = Rotation.from_rotvec(np.stack([0.45 * np.sin(t / 23), 0.3 * np.sin(t / 31), 0.2 * np.sin(t / 17)], 1)
                                + np.outer(np.clip((t - 10) / 20, 0, 1), [0, lean, 0]))
    shift = np.stack([2.0 * t, 40 * np.sin(t / 50), np.zeros(FRAMES)], 1)[:, None]
    trunk = np.einsum("fij,kj->fki", trunk_turn, TRUNK) + shift
    head = np.einsum("fij,fjk,lk->fli", trunk_turn, bend.as_matrix(), HEAD) + (trunk_turn @ NECK)[:, None] + shift
    return np.concatenate([trunk, head], axis=1) + np.random.default_rng(seed).normal(0.0, 1.0, (FRAMES, 7, 3))


def _found(labeled: np.ndarray) -> list[tuple[int, int, int, int]]:
    neighbours = MarkerState.from_first_frame(labeled[0], n_neighbours=6).neighbours
    return [(e.a, e.b, e.start, e.stop) for e in take_exchanges(labeled, labeled[0], neighbours)]


def _exchanged(take: np.ndarray) -> np.ndarray:
    labeled = take.copy()
    labeled[EXCHANGED, [TEMPLE, EAR]] = take[EXCHANGED, [EAR, TEMPLE]]
    return labeled


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pair_no_marker_is_rigid_with_is_given_back_by_its_differences(
    seed: int, monkeypatch: pytest.MonkeyPatch,
) -> None:
    labeled = _exchanged(_take(seed))
    neighbours = MarkerState.from_first_frame(labeled[0], n_neighbours=6).neighbours
    _, rigid = rigid_pairs(labeled, labeled[0], neighbours)
    assert rigid[TEMPLE, EAR] and not (rigid[TEMPLE] & rigid[EAR]).any()  # the pair is rigid, nothing with it
    ((a, b, start, stop),) = _found(labeled)
    assert (a, b) == (TEMPLE, EAR) and abs(start - EXCHANGED.start) <= 2 and abs(stop - EXCHANGED.stop) <= 2
    monkeypatch.setattr(take_exchange_module, "difference_witnesses", lambda *args: None)
    assert _found(labeled) == []  # without them nothing judges the pair


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pose_the_first_frame_did_not_have_does_not_hide_the_exchange(
    seed: int, monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The head leans 17 degrees after the first frame and stays so (the basket sprint's
    athlete, seated, leans in): each difference D_j sits off the first frame's for the rest of
    the take, so held to the take's s_j the right labels themselves fit no better than
    ``FIT_COST`` allows, and the exchanged stretch stayed. The fit's spread, widened by how
    far the first frame lies from the take's typical |D_j|, gives it back."""
    take = _take(seed, lean=0.3)
    ((a, b, start, stop),) = _found(_exchanged(take))
    assert (a, b) == (TEMPLE, EAR) and abs(start - EXCHANGED.start) <= 2 and abs(stop - EXCHANGED.stop) <= 2
    assert _found(take) == []
    monkeypatch.setattr(take_exchange_module, "fit_spread", lambda apart, apart0, sd: sd)
    assert _found(_exchanged(take)) == []  # held to the take's spread alone


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("lean", [0.0, 0.3])
def test_right_labels_of_such_a_pair_are_left_alone(seed: int, lean: float) -> None:
    assert _found(_take(seed, lean)) == []


def test_the_fit_spread_widens_by_the_first_frames_distance_from_the_typical_difference() -> None:
    apart = np.array([[50.0, -20.0], [-54.0, np.nan], [52.0, -21.0]])  # an exchanged frame flips the sign
    widened = fit_spread(apart, np.array([70.0, -20.0]), np.array([3.0, 4.0]))
    assert widened == pytest.approx([np.hypot(3.0, 18.0), np.hypot(4.0, 0.5)])


def test_a_marker_both_are_as_far_from_is_no_witness() -> None:
    """Marker 2 sits 66 mm nearer the ear, marker 1 as far from both (its difference near 0,
    which an exchange leaves where it was): 2 witnesses, 1 does not."""
    take = _take(0)
    d0 = np.linalg.norm(take[0][:, None] - take[0][None], axis=2)
    for marker, witnesses in ((1, False), (2, True)):
        found = difference_witnesses(take, TEMPLE, EAR, np.array([marker]), d0)
        assert (found is not None) == witnesses
    found = difference_witnesses(take, TEMPLE, EAR, np.arange(5), d0)
    assert found is not None
    apart, apart0, sd = found
    assert np.all(np.abs(apart0) >= CAP * sd) and apart.shape == (FRAMES, len(sd))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_labels_that_move_the_pair_apart_are_no_exchange_of_it(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The differences say "exchanged" in both labelings below (their witnesses moved with the
    labels, as on the tennis serve's first pass); only the pair's own distance tells the
    exchanged pair (kept) from labels 15 mm farther apart than the pair ever is (refused)."""
    take = _take(seed)
    exchanged = _exchanged(take)
    pushed = exchanged.copy()
    axis = take[EXCHANGED, TEMPLE] - take[EXCHANGED, EAR]
    pushed[EXCHANGED, EAR] += 15.0 * axis / np.linalg.norm(axis, axis=1, keepdims=True)
    real = take_exchange_module.difference_witnesses
    monkeypatch.setattr(take_exchange_module, "difference_witnesses", lambda _, *rest: real(exchanged, *rest))
    assert [(a, b) for a, b, *_ in _found(exchanged)] == [(TEMPLE, EAR)]
    assert _found(pushed) == []
    monkeypatch.setattr(take_exchange_module, "pair_offset", lambda own, *_: np.zeros((len(own), 1)))
    assert [(a, b) for a, b, *_ in _found(pushed)] == [(TEMPLE, EAR)]  # the pair's distance is what refuses
