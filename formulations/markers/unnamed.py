"""Unnamed tracks: points no marker holds that persist from frame to frame.

A take's points are not all its named markers': markers the labeled frame does not name
(absent there), steady reflections. Priced as clutter, each of their points is a false
alarm of its own, every frame, so a lost marker that takes such a chain pays one costly
reappearance and then saves a miss every frame; the window hands it the chain, and the
marker whose point it later meets is pushed off in turn (03_rolling: six markers absent at
the start frame, their points taken by lost arm and head markers one after another).

Here such a chain is an object of the window, competing for its points with the named
markers (``cloud_candidates``: the step likelihood of a typical marker, and for its shape
what a right label pays in that window, the median of the seen markers' best shape costs):

- a **seed**: a point at the template that no seen marker holds, with a point of the frame
  before within ``reach`` of it (a track, not a one-frame ghost), moving at that step;
- a **birth**: a point of a window frame that no point of the frame before continues
  (``_unexplained``: within ``link_radius`` of where that point's last step puts it, or
  within ``reach`` of a point with no step), or a point of the template no point before
  it is within ``reach`` of (not a seed): something appeared. It must be followed for at
  least ``MIN_BIRTH_POINTS`` frames, the frames after the window included;
- points the window's nearest-neighbour guide gave a marker seen the frame before are
  left out: they continue that marker's track, unless the guide's track of that marker
  made a step in the window its own motion does not explain (``_guide_holds``): it then
  took something that appeared as the marker vanished (03_rolling's LRUA1, lost, onto the
  back of the head as that point came back at frame 708; Vicon's MEDH onto STYLu's point
  33 mm away, a step ten times its own).

Each is followed frame to frame at constant velocity, linked by an optimal assignment
inside ``link_radius`` of its prediction (``reach`` while its velocity is unknown), and
ends where nothing is there. Missing costs an unnamed object nothing (such a point may
vanish); a birth enters at

    b = log(lambda_FA / beta),

the odds of a point being a newcomer rather than clutter: lambda_FA the spare points per
frame, beta the births per frame (the window's births over its frames, with a prior of
``PRIOR_BIRTHS`` in ``PRIOR_FRAMES``).

Only where the take is known to hold markers its labeled frame does not name
(``WindowSurround.known``: ``track --start`` on a frame some markers are absent from).
Where every marker is named, a point no marker holds is mostly a named marker's own, back
from a gap the window did not read as such, and an unnamed track then keeps it from its
marker: on the seed-0 accuracy matrix (85 generated rows, every marker named) seeds and
births everywhere took 97.11 -> 96.97 % (wheelchair racing's 30 mm plates down 0.3-4.4
points), seeds alone 96.97 %, births without the guide's points left out 95.81 %.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from formulations.markers.guide import Gate, GuideTrack
from formulations.markers.lengths import lengths
from formulations.markers.state import MarkerState

HELD_MM = 1e-6  # a point this close to a seen marker is that marker's
MIN_BIRTH_POINTS = 3  # a birth followed for fewer frames is left to clutter (a one-frame ghost)
REACH_PERCENTILE = 90.0  # of the seen markers' speeds: one wrong jump must not widen every reach
PRIOR_BIRTHS, PRIOR_FRAMES = 1.0, 20.0  # beta's prior: one birth in a window's worth of frames


@dataclass(frozen=True)
class UnnamedChains:
    """Unnamed objects of one window.

    Attributes:
        template_location: ``(U, 3)`` position at the template (a birth: its first point).
        seeded: ``(U,)`` True for a seed (seen at the template), False for a birth.
        point: ``(U, M)`` index of the point taken in each window frame, -1 none.
        motion: ``(U, M, 3)`` expected step into each frame (NaN where unknown).
    """

    template_location: np.ndarray
    seeded: np.ndarray
    point: np.ndarray
    motion: np.ndarray

    @classmethod
    def empty(cls, m: int) -> UnnamedChains:
        """No unnamed object in a window of ``m`` frames."""
        return cls(np.zeros((0, 3)), np.zeros(0, bool), np.full((0, m), -1), np.zeros((0, m, 3)))

    @property
    def n_objects(self) -> int:
        return len(self.seeded)

    def births_per_frame(self) -> float:
        """beta: births per frame, the window's against the prior."""
        births = int(np.count_nonzero(~self.seeded))
        return (births + PRIOR_BIRTHS) / (int(self.point.shape[1]) + PRIOR_FRAMES)


@dataclass(frozen=True)
class WindowSurround:
    """The points next to a window that its unnamed tracks are followed through.

    Attributes:
        template, before: ``(K, 3)`` points of the template frame and of the frame before it.
        after: Points of the frames after the window, where a birth in its last frames may
            be followed to ``MIN_BIRTH_POINTS`` (its candidates stay in the window).
        known: Unnamed markers known to be in the take (left out of its labeled frame).
        coexisting: ``(N, K)`` True where named marker n, unseen, was last seen apart from
            the track of template point k (``coexistence``); None: not known.
    """

    template: np.ndarray
    before: np.ndarray
    after: list[np.ndarray]
    known: int = 0
    coexisting: np.ndarray | None = None


def unnamed_chains(
    state: MarkerState, around: WindowSurround, frames: list[np.ndarray], gate: Gate, guide: GuideTrack,
) -> UnnamedChains:
    """The window's unnamed objects (module doc).

    Args:
        state: The named markers at the template.
        around: The template frame's points, the frame's before and the frames' after.
        frames: ``(K_f, 3)`` points of window frames 1..M.
        gate: The markers' gate: a chain links within ``motion_sigmas`` sd (3D) of a typical
            marker's step residual (the median learned variance) of its prediction; a point
            of unknown velocity within that of the ``REACH_PERCENTILE`` speed of the seen markers.
        guide: The window's nearest-neighbour track: a point it gave a marker seen the frame
            before continues that marker's track and is no unnamed track's.
    """
    if not around.known:
        return UnnamedChains.empty(len(frames))
    reach, link_radius = chain_radii(state, gate)
    free = around.template[_farther(around.template, state.position[state.visible], HELD_MM)]
    tracked, step = _predecessors(free, around.before, reach)
    chains = [_Chain(p, v, 0, True) for p, v in zip(free[tracked], step[tracked])]
    chains += [_Chain(p, None, 0, False) for p in free[~tracked]]  # appeared at the template: born there
    earlier, previous = around.before, around.template
    holds = _guide_holds(guide, state, frames, reach, link_radius)
    for f, points in enumerate([*frames, *around.after], start=1):
        held_now = holds[f - 1] if f <= len(frames) else np.zeros(len(points), bool)
        linked = _link(chains, points, ~held_now, f, link_radius, reach)
        if f <= len(frames):
            appeared = _unexplained(points, previous, earlier, reach, link_radius) & ~linked & ~held_now
            chains += [_Chain(points[k], None, f, False, {f: int(k)}) for k in np.flatnonzero(appeared)]
        earlier, previous = previous, points
    kept = [c for c in chains if c.seeded or len(c.taken) + (c.born == 0) >= MIN_BIRTH_POINTS]
    return _assembled([c for c in kept if c.taken], len(frames))


def _guide_holds(guide: GuideTrack, state: MarkerState, frames: list[np.ndarray], reach: float, link_radius: float,
                 ) -> list[np.ndarray]:
    """Per window frame, the points the guide gave a marker seen the frame before
    (``GuideTrack.continued``), less those of a marker whose guided track has made a step
    its own motion does not explain (``_unexplained``) in the window: the guide then took
    something that appeared as the marker vanished."""
    held_all = [guide.continued(f, len(points)) for f, points in enumerate(frames, start=1)]
    if guide.point is None:
        return held_all
    n = len(state.position)
    last = np.where(state.visible[:, None], state.position, np.nan)
    step = np.where((state.visible & state.velocity_known)[:, None], state.velocity, np.nan)
    broken = np.zeros(n, bool)
    holds = []
    for f, points in enumerate(frames, start=1):
        took = guide.point[f - 1]
        now = np.full((n, 3), np.nan)
        now[took >= 0] = points[took[took >= 0]]
        stepped = np.asarray(np.isfinite(step).all(axis=1))
        explained = _continues(lengths(now - (last + step)), lengths(now - last),
                               stepped, reach, link_radius)
        broken |= ~explained & np.isfinite(now).all(axis=1) & np.isfinite(last).all(axis=1)
        held = held_all[f - 1].copy()
        held[took[(took >= 0) & broken]] = False
        holds.append(held)
        step, last = now - last, now
    return holds


def chain_radii(state: MarkerState, gate: Gate) -> tuple[float, float]:
    """(reach, link radius) in mm (``unnamed_chains``): how far a point may step in one frame
    with its velocity unknown, and off where its own last step puts it."""
    link_radius = gate.motion_sigmas * float(np.sqrt(3 * np.median(state.motion_var)))
    moving = state.visible & state.velocity_known
    speed = np.linalg.norm(state.velocity[moving], axis=1)
    return (float(np.percentile(speed, REACH_PERCENTILE)) if len(speed) else gate.radius_mm) + link_radius, link_radius


def _predecessors(free: np.ndarray, before: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """For each of the points ``free``, whether the frame ``before`` has a point within
    ``reach``, and the step from its nearest one."""
    if not len(before) or not len(free):
        return np.zeros(len(free), bool), np.zeros((len(free), 3))
    near = before[cdist(free, before).argmin(axis=1)]
    return lengths(free - near) <= reach, free - near


@dataclass
class _Chain:
    """One unnamed track being followed: where it is, its step, the point taken per frame."""

    last: np.ndarray
    velocity: np.ndarray | None
    last_frame: int
    seeded: bool
    taken: dict[int, int] = field(default_factory=dict)
    steps: dict[int, np.ndarray] = field(default_factory=dict)
    first: np.ndarray = field(init=False)
    born: int = field(init=False)

    def __post_init__(self) -> None:
        self.first, self.born = self.last.copy(), self.last_frame


def _link(chains: list[_Chain], points: np.ndarray, free: np.ndarray, f: int, link_radius: float, reach: float,
          ) -> np.ndarray:
    """Extend the chains alive at frame f - 1 onto the ``free`` ``points`` of frame f; True where a point was linked."""
    linked = np.zeros(len(points), bool)
    alive = [c for c in chains if c.last_frame == f - 1]
    if not alive or not len(points):
        return linked
    predicted = np.array([c.last + (c.velocity if c.velocity is not None else 0.0) for c in alive])
    stepped = np.array([c.velocity is not None for c in alive])
    distance = cdist(predicted, points)  # from the last point where there is no step
    inside = _continues(distance, distance, stepped[:, None], reach, link_radius) & free[None, :]
    rows, cols = linear_sum_assignment(np.where(inside, distance, 1e9))
    for r, k in zip(rows, cols):
        if not inside[r, k]:
            continue
        chain = alive[r]
        # A birth's second point has no velocity to be judged by: its own step is expected.
        chain.steps[f] = chain.velocity if chain.velocity is not None else points[k] - chain.last
        chain.velocity, chain.last, chain.last_frame = points[k] - chain.last, points[k], f
        chain.taken[f] = int(k)
        linked[k] = True
    return linked


def _assembled(chains: list[_Chain], m: int) -> UnnamedChains:
    point = np.full((len(chains), m), -1)
    motion = np.full((len(chains), m, 3), np.nan)
    for u, chain in enumerate(chains):
        for f, k in chain.taken.items():
            if f <= m:
                point[u, f - 1] = k
        for f, step in chain.steps.items():
            if f <= m:
                motion[u, f - 1] = step
    location = np.array([c.first for c in chains]).reshape(-1, 3)
    return UnnamedChains(location, np.array([c.seeded for c in chains], bool), point, motion)


def _unexplained(points: np.ndarray, previous: np.ndarray, earlier: np.ndarray, reach: float, link_radius: float,
                 ) -> np.ndarray:
    """True for the points no point of the frame before continues: within ``link_radius`` of
    where that point's own last step (from its nearest point of the frame before it, within
    ``reach``) puts it, or within ``reach`` of it where it has no such step. A marker moving
    3 mm a frame does not reach a point 33 mm away (Vicon: MEDH vanishes as STYLu appears
    there)."""
    if not len(previous) or not len(points):
        return np.ones(len(points), bool)
    stepped, step = _predecessors(previous, earlier, reach)
    continued = _continues(cdist(points, previous + step), cdist(points, previous), stepped[None, :], reach, link_radius)
    return np.asarray(~continued.any(axis=1))


def _continues(to_predicted: np.ndarray, to_last: np.ndarray, stepped: np.ndarray, reach: float, link_radius: float,
               ) -> np.ndarray:
    """Whether a point continues a track: within ``link_radius`` of where the track's last step
    puts it, or, for a track with no step yet (``stepped`` False), within ``reach`` of its last point."""
    return np.asarray(np.where(stepped, to_predicted <= link_radius, to_last <= reach))


def _farther(points: np.ndarray, others: np.ndarray, distance: float) -> np.ndarray:
    """True for the points with no point of ``others`` within ``distance``."""
    if not len(others) or not len(points):
        return np.ones(len(points), bool)
    return np.asarray(cdist(points, others).min(axis=1) > distance)
