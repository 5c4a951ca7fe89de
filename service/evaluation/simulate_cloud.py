"""Cloud-mode simulator: labeled trajectories -> noisy, gappy, ghosted, shuffled 3D points."""

import numpy as np

from service.errors import InputError
from service.evaluation.scenario import Scenario
from service.evaluation.simulated import SimulatedCapture
from service.io.recording import Recording, UnlabeledCloud


def simulate_cloud(truth: Recording, scenario: Scenario) -> SimulatedCapture:
    """Turn labeled trajectories into the unlabeled point clouds a 3D capture would give.

    Steps, all driven by one ``numpy.random.default_rng(scenario.seed)`` so that the
    result is a function of the seed:

    1. Keep frames ``[start_frame, start_frame + frames)`` (``frames = 0``: to the end).
    2. Add ``N(0, noise_mm^2)`` noise to each coordinate of every sample.
    3. Delete samples in bursts with a per-marker visible/deleted Markov chain (see
       ``Scenario.deletion_transitions``); the first frame is never deleted, and samples
       missing in the source stay missing.
    4. Add ``Poisson(ghosts_per_frame)`` ghosts per frame, each at a uniformly chosen
       marker of that frame plus an ``N(0, ghost_spread_mm^2 I)`` offset.
    5. Shuffle the points of each frame.
    6. Leave ``unnamed_markers`` markers unnamed: their points stay, scored as ghosts.

    Args:
        truth: Labeled trajectories, millimetres.
        scenario: A scenario with ``mode = "cloud"``.

    Returns:
        The cloud, each point's true marker, the clean slice and the labeled first frame.

    Raises:
        InputError: If the slice has fewer than 2 frames or a marker has no position in its first frame.
    """
    if scenario.mode != "cloud":
        raise InputError(f"simulate_cloud needs mode 'cloud', got '{scenario.mode}'")
    clean = _slice(truth, scenario)
    rng = np.random.default_rng(scenario.seed)
    present = ~clean.missing()
    noisy = clean.positions + rng.normal(0.0, scenario.noise_mm, clean.positions.shape)
    visible = present & ~_deletions(rng, present.shape, scenario)
    ghosts = _ghosts(rng, clean.positions, present, scenario)
    points, point_marker = _shuffled_frames(rng, noisy, visible, ghosts)
    named = _named(rng, clean.n_markers, scenario.unnamed_markers)
    renumber = np.full(clean.n_markers + 1, -1)  # index -1 (a ghost) stays -1
    renumber[named] = np.arange(len(named))
    names = [clean.names[i] for i in named]
    return SimulatedCapture(
        cloud=UnlabeledCloud(points=points, rate=clean.rate),
        point_marker=[renumber[m] for m in point_marker],
        truth=Recording(names=names, positions=clean.positions[:, named], rate=clean.rate),
        first_frame=Recording(names=names, positions=noisy[:1, named], rate=clean.rate),
        scenario=scenario,
    )


def _named(rng: np.random.Generator, markers: int, unnamed: int) -> np.ndarray:
    """Indices of the markers that keep their names, in order (drawn last: the rest of the
    simulation does not depend on ``unnamed``)."""
    if unnamed == 0:
        return np.arange(markers)
    if unnamed >= markers:
        raise InputError(f"scenario key 'unnamed_markers' {unnamed}: the recording has {markers} markers")
    return np.sort(rng.choice(markers, markers - unnamed, replace=False))


def _slice(truth: Recording, scenario: Scenario) -> Recording:
    """The requested frames, gaps written as NaN, with a complete first frame."""
    if truth.n_markers == 0:
        raise InputError("the recording has no markers")
    start, stop = scenario.frame_span(truth.n_frames)
    positions = truth.positions[start:stop].copy()
    # Some exporters write gaps as (0, 0, 0); NaN keeps them out of any arithmetic.
    positions[truth.missing()[start:stop]] = np.nan
    clean = Recording(names=list(truth.names), positions=positions, rate=truth.rate)
    absent = np.flatnonzero(clean.missing()[0])
    if absent.size:
        best, count = truth.fullest_frame()
        raise InputError(
            f"marker {clean.names[absent[0]]} has no position in the first frame (frame {start}); scenario key "
            f"start_frame picks another (frame {best} has {count} of {truth.n_markers} markers)"
        )
    return clean


def _deletions(rng: np.random.Generator, shape: tuple[int, int], scenario: Scenario) -> np.ndarray:
    """``(frames, markers)`` bool deletion mask from the two-state Markov chain.

    ``deleted[f] = deleted[f-1] ? (u >= p_leave) : (u < p_enter)`` with ``u ~ U[0, 1)``,
    starting visible in frame 0. The recursion is sequential in time, so the loop runs
    over frames and is vectorised over markers.
    """
    p_enter, p_leave = scenario.deletion_transitions
    u = rng.random(shape)
    deleted = np.zeros(shape, dtype=bool)
    for f in range(1, shape[0]):
        deleted[f] = np.where(deleted[f - 1], u[f] >= p_leave, u[f] < p_enter)
    return deleted


def _ghosts(
    rng: np.random.Generator, clean: np.ndarray, present: np.ndarray, scenario: Scenario
) -> list[np.ndarray]:
    """Per frame, a ``(ghosts, 3)`` array of spurious points near the body.

    The anchor marker is drawn among those with a true position, occluded or not: the
    body that reflects stray light is there either way. A frame with no marker at all has
    no body to be near, so its ghosts are dropped.
    """
    n_frames = clean.shape[0]
    frame = np.repeat(np.arange(n_frames), rng.poisson(scenario.ghosts_per_frame, n_frames))
    n_present = present.sum(axis=1)[frame]
    # Row-wise stable argsort of ~present lists each frame's present markers first,
    # so the k-th present marker is order[f, k] with k uniform in [0, n_present).
    order = np.argsort(~present, axis=1, kind="stable")
    pick = (rng.random(frame.size) * n_present).astype(int)
    offset = rng.normal(0.0, scenario.ghost_spread_mm, (frame.size, 3))
    keep = n_present > 0
    frame = frame[keep]
    ghosts = clean[frame, order[frame, pick[keep]]] + offset[keep]
    return np.split(ghosts, np.cumsum(np.bincount(frame, minlength=n_frames))[:-1])


def _shuffled_frames(
    rng: np.random.Generator, noisy: np.ndarray, visible: np.ndarray, ghosts: list[np.ndarray]
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per frame, the visible samples and the ghosts in random order, with their markers."""
    points, point_marker = [], []
    for f in range(noisy.shape[0]):
        markers = np.flatnonzero(visible[f])
        frame_points = np.concatenate([noisy[f, markers], ghosts[f]])
        frame_markers = np.concatenate([markers, np.full(len(ghosts[f]), -1)])
        perm = rng.permutation(len(frame_markers))
        points.append(frame_points[perm])
        point_marker.append(frame_markers[perm])
    return points, point_marker
