"""Best view by sliding-window DP (Jiang et al. Sec. III) against brute force and the paper's pseudo-code."""

import itertools

import numpy as np
import pytest

from formulations.best_view import relative_costs, select_views
from formulations.errors import FormulationError


def window_objective(costs, sequence, previous, switch_cost):
    """(1) of the selection module: view costs plus lambda per switch, b_{-1} = previous."""
    switches = np.count_nonzero(np.diff(np.r_[previous, sequence]))
    return costs[np.arange(len(sequence)), sequence].sum() + switch_cost * switches


def brute_force_views(costs, switch_cost, window):
    """One object's (F, M) costs: every camera sequence of every window tried, b_0 of the cheapest kept."""
    n_frames, n_cameras = costs.shape
    previous, chosen = int(np.argmin(costs[0])), []
    for start in range(n_frames):
        part = costs[start : start + window]
        best = min(itertools.product(range(n_cameras), repeat=len(part)),
                   key=lambda seq: window_objective(part, np.array(seq), previous, switch_cost))
        previous = best[0]
        chosen.append(previous)
    return np.array(chosen)


def jiang_pseudo_code(costs, switch_cost, window):
    """The paper's "Algorithm: Best View Selection", steps 1-6, transcribed loop for loop.

    d(x, y) is 0 for the same camera and 1 for a switch; t is the cost of the cheapest
    sequence ending at (n, m), prev its predecessor; a window near the end is shorter.
    """
    n_frames, M = costs.shape
    d = lambda x, y: 0.0 if x == y else 1.0  # noqa: E731
    b_previous = int(np.argmin(costs[0]))                                   # step 1
    output = []
    for start in range(n_frames):
        N = min(window, n_frames - start)
        c = costs[start : start + N]
        t = {(-1, m): (0.0 if m == b_previous else np.inf) for m in range(M)}  # step 2
        prev = {}
        for n in range(N):                                                  # step 3
            for m in range(M):
                v = min(range(M), key=lambda i: switch_cost * d(m, i) + t[(n - 1, i)])
                t[(n, m)] = c[n, m] + switch_cost * d(m, v) + t[(n - 1, v)]
                prev[(n, m)] = v
        f = min(range(M), key=lambda m: t[(N - 1, m)])                      # step 4
        for n in range(N - 2, -1, -1):                                      # step 5
            f = prev[(n + 1, f)]
        output.append(f)                                                    # b_0* = f_0
        b_previous = f                                                      # step 6
    return np.array(output)


def random_costs(seed, frames, objects, cameras):
    return np.random.default_rng(seed).random((frames, objects, cameras))


@pytest.mark.parametrize("ruled_out", [False, True], ids=["every-camera", "cameras-ruled-out"])
@pytest.mark.parametrize("seed", range(12))
def test_dp_equals_brute_force_over_every_allowed_camera_sequence(seed, ruled_out):
    rng = np.random.default_rng(100 + seed)
    frames, cameras, window = int(rng.integers(4, 9)), int(rng.integers(2, 4)), int(rng.integers(1, 5))
    switch_cost = float(rng.uniform(0.0, 1.5))
    costs = random_costs(seed, frames, 2, cameras)
    allowed = np.ones(costs.shape, bool)
    if ruled_out:  # each frame keeps one allowed camera
        allowed = rng.random(costs.shape) < 0.6
        allowed[np.arange(frames)[:, None], np.arange(2), rng.integers(0, cameras, (frames, 2))] = True
    chosen = select_views(costs, switch_cost, window, allowed if ruled_out else None)
    assert np.take_along_axis(allowed, chosen[..., None], axis=2).all()
    for k in range(2):  # brute force: a ruled-out camera's sequences cost +inf
        expected = brute_force_views(np.where(allowed[:, k], costs[:, k], np.inf), switch_cost, window)
        np.testing.assert_array_equal(chosen[:, k], expected)


def test_a_ruled_out_camera_is_left_even_where_staying_would_tie_with_a_switch():
    """Camera 0 best in frame 0, then blind: it costs 1 like every camera of frame 1 (the
    object is seen by none), so staying there ties with a switch at lambda = 1 and was kept."""
    costs = np.array([[0.0, 0.5], [1.0, 1.0], [1.0, 0.0]])[:, None, :]
    allowed = np.array([[True, True], [False, True], [False, True]])[:, None, :]
    assert select_views(costs, 1.0, 30)[:, 0].tolist() == [0, 0, 0]
    assert select_views(costs, 1.0, 30, allowed)[:, 0].tolist() == [0, 1, 1]


@pytest.mark.parametrize("allowed,message", [
    (np.ones((3, 1, 3), bool), "shape"),
    (np.array([[[True, True]], [[False, False]], [[True, False]]]), "allowed camera"),
])
def test_a_bad_allowed_mask_is_one_line(allowed, message):
    with pytest.raises(FormulationError, match=message):
        select_views(np.zeros((3, 1, 2)), 1.0, 2, allowed)


@pytest.mark.parametrize("seed", range(8))
def test_dp_reproduces_jiangs_pseudo_code(seed):
    rng = np.random.default_rng(200 + seed)
    window, switch_cost = int(rng.integers(1, 8)), float(rng.uniform(0.0, 2.0))
    costs = random_costs(seed, 30, 3, 4)
    chosen = select_views(costs, switch_cost, window)
    for k in range(3):
        np.testing.assert_array_equal(chosen[:, k], jiang_pseudo_code(costs[:, k], switch_cost, window))


def test_a_one_frame_blip_is_ignored_and_a_lasting_change_followed_on_time():
    # Worked by hand from (1). A noisy frame 2 favours camera 1 by 0.6 - 0 = 0.6: staying
    # costs 0.6, switching there and back 2 lambda (2 at lambda = 1, 0.4 at lambda = 0.2).
    blip = np.array([[0, 0.5], [0, 0.5], [0.6, 0], [0, 0.5], [0, 0.5]])[:, None, :]
    assert select_views(blip, 1.0, 3)[:, 0].tolist() == [0, 0, 0, 0, 0]
    assert select_views(blip, 0.2, 3)[:, 0].tolist() == [0, 0, 1, 0, 0]
    # From frame 3 camera 1 is better by 0.3 a frame, a switch costs 0.5: a one-frame
    # greedy filter never pays for it; a 3-frame window sees frames 3 and 4 (0.6 > 0.5)
    # from frame 2 on and switches at frame 3, where the change happens.
    lasting = np.array([[0, 0.3]] * 3 + [[0.3, 0]] * 3)[:, None, :]
    assert select_views(lasting, 0.5, 1)[:, 0].tolist() == [0] * 6
    assert select_views(lasting, 0.5, 3)[:, 0].tolist() == [0, 0, 0, 1, 1, 1]


@pytest.mark.parametrize("window", [1, 4, 25])
def test_no_switch_cost_is_the_per_frame_best(window):
    costs = random_costs(7, 40, 5, 4)
    np.testing.assert_array_equal(select_views(costs, 0.0, window), np.argmin(costs, axis=2))


@pytest.mark.parametrize("window", [1, 3, 10])
def test_a_switch_dearer_than_any_window_never_switches(window):
    costs = random_costs(8, 60, 4, 3)
    chosen = select_views(costs, window * 1.01, window)  # costs lie in [0, 1): a window gains < window
    np.testing.assert_array_equal(chosen, np.broadcast_to(np.argmin(costs[0], axis=1), chosen.shape))
    # and the per-frame best does switch on these costs, so the test can fail
    assert np.count_nonzero(np.diff(np.argmin(costs, axis=2), axis=0)) > 0


def test_more_switch_cost_never_means_more_switches_on_average():
    costs = random_costs(9, 200, 20, 4)
    switches = [np.count_nonzero(np.diff(select_views(costs, lam, 8), axis=0)) for lam in (0.0, 0.3, 1.0, 3.0)]
    assert switches == sorted(switches, reverse=True) and switches[0] > switches[-1]


def test_relative_costs_put_the_best_camera_at_zero_and_an_unseen_one_at_one():
    quality = np.array([[4.0, 2.0, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(relative_costs(quality), [[0.0, 0.5, 1.0], [1.0, 1.0, 1.0]])


@pytest.mark.parametrize("costs,switch_cost,window,message", [
    (np.zeros((3, 1)), 1.0, 2, "shape"),
    (np.array([[[0.0, np.nan]]]), 1.0, 2, "finite"),
    (np.zeros((3, 1, 2)), -1.0, 2, "switch cost"),
    (np.zeros((3, 1, 2)), 1.0, 0, "window"),
    (np.zeros((3, 1, 0)), 1.0, 2, "camera"),
])
def test_bad_input_is_one_line(costs, switch_cost, window, message):
    with pytest.raises(FormulationError, match=message):
        select_views(costs, switch_cost, window)


def test_no_frames_choose_nothing():
    assert select_views(np.zeros((0, 2, 3)), 1.0, 5).shape == (0, 2)
