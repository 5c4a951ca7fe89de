"""Recovery of rigid clusters whose labels turn them: a permutation their distances cannot see.

Racing and sports labs put three markers on a rigid plate, often an equilateral triangle
(the wheelchair-racing take's gloves and scapulae: 43, 43, 43 mm). Every permutation of
such a cluster keeps every distance, so neither the window's shape costs nor the exchange
and mirror repairs (``exchange``, ``mirror``) can tell one reading from another, and a hand
moving 80 mm per frame against 43 mm spacing aliases: its labels rotate round the plate and
stay so.

What does tell them apart is that a rigid body turns smoothly. Each time a cluster's three
markers are labeled, each permutation pi of the current labels has a best rigid fit (Kabsch)
of its last full sighting onto the current triangle, with residual e_pi and rotation R_pi.
Against the rotation expected, R_hat (one frame on, the cluster's last step again: constant
angular velocity; over a gap, or before any step, none), the turn off the expected is

    theta_pi = angle(R_pi R_hat^T).

A permutation of a triangle that keeps its distances is one of its symmetries, and its
rotation lies at least 120 degrees (a 3-cycle) or 180 degrees (an exchange) from the true
one. So when the labels and a permutation both fit (e_id, e_pi <= ``FIT_TOLERANCE_MM``: both
sightings hold the same triangle, no foreign point), the permutation turns off the expected by
less than ``MIN_TURN_GAP_DEG`` (half the nearest symmetry) and the labels by that much more,
the labels are permuted back, from that frame to the end of the window. Where both turn far
off the expected (a tennis hand at the strike, 50 Hz) neither reading is the smooth one, and
nothing is done. Across a gap of g frames this is done only while the
cluster's last turn rate times g stays below that half: a plate turning 25 degrees a frame
may have turned by a symmetry in five, and then nothing tells.

A cluster is three markers whose learned distances to one another vary by at most
``RIGID_SD_MM`` (as in ``mirror``; skin markers that slide turn no less smoothly, but need
not keep a permutation's fit), with a least altitude of ``MIN_ALTITUDE_MM`` (a flat triangle
has no turn to read). Only its symmetries are tried: the permutations that keep its learned
side lengths within ``SYMMETRY_MM`` (all six for an equilateral plate, one exchange for an
isosceles one, none for a scalene one, which the distances already read); otherwise a
reading the window chose by a few mm of shape would be turned back by the turn alone.

The repair runs on each window's solution, before the marker state is
carried through it, so that the next window's predictions follow the repaired labels. Each
plate's last whole sighting, its age and the turn rate then are kept in the marker state
(``MarkerState.plate_*``, ``_Sightings.remembered``), so a plate hidden at a window's template
is read against the sighting before it when it comes back whole (racing's left scapula, lost
across a template and back a third of a turn round, stayed so to the end of the take).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import permutations

import numpy as np

from formulations.markers.means import axis_mean
from formulations.markers.mirror import LearnedPairs, rigid_bound, rigid_groups
from formulations.markers.state import MarkerState

# Learned side lengths that agree within 2 mm the window's distance costs cannot tell apart
# at a few mm of noise; a plate built symmetric agrees within a few tenths (racing: 43.0-43.2).
SYMMETRY_MM = 2.0
FIT_TOLERANCE_MM = 5.0  # a permutation fits "as well" within a few mm of skin motion and noise
MIN_TURN_GAP_DEG = 60.0  # half the 120 degrees between an equilateral triangle's symmetries
# A triangle's turn is read from its corners' offsets: at altitude h and per-axis noise sigma
# its sd is about sigma / h, 15 degrees at 4 mm, a quarter of the gap it must show. Flatter
# clusters (markers in a line, copied columns on one point) have no turn to read.
MIN_ALTITUDE_MM = 15.0
PERMUTATIONS = np.array(list(permutations(range(3))))  # identity first
IDENTITY = PERMUTATIONS[:1]


def rigid_triples(state: MarkerState) -> tuple[np.ndarray, np.ndarray]:
    """``(T, 3)`` distinct triples of markers rigid with one another (each marker with its two
    nearest rigid neighbours, as ``mirror.rigid_groups`` makes quadruples) that distances cannot
    read, and ``(T, 6)`` which ``PERMUTATIONS`` keep their learned side lengths within
    ``SYMMETRY_MM``: the readings only the turn tells apart."""
    learned = LearnedPairs.of(state)
    groups, found = rigid_groups(np.ones(len(state.position), dtype=bool), learned, rigid_bound(state), 3)
    if not found.any():
        return np.zeros((0, 3), dtype=int), np.zeros((0, len(PERMUTATIONS)), dtype=bool)
    triples = np.unique(np.sort(groups[found], axis=1), axis=0)
    sides = _sides(learned.mean, triples[:, None, :])[:, 0]
    tall = _altitude(sides) >= MIN_ALTITUDE_MM
    triples, sides = triples[tall], sides[tall]
    symmetric = (np.abs(_sides(learned.mean, triples[:, PERMUTATIONS]) - sides[:, None, :]) <= SYMMETRY_MM).all(axis=2)
    keep = symmetric[:, 1:].any(axis=1)
    return triples[keep], symmetric[keep]


def _sides(mean: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """``(T, P, 3)`` learned lengths of sides 01, 12, 02 of ``(T, P, 3)`` triangles of marker indices."""
    result: np.ndarray = mean[corners[..., [0, 1, 0]], corners[..., [1, 2, 2]]]
    return result


def _altitude(sides: np.ndarray) -> np.ndarray:
    """``(T,)`` each triangle's least altitude (mm) from its ``(T, 3)`` side lengths (Heron)."""
    half = sides.sum(axis=1) / 2.0
    area = np.sqrt(np.maximum(half * np.prod(half[:, None] - sides, axis=1), 0.0))
    result: np.ndarray = 2.0 * area / np.maximum(sides.max(axis=1), 1e-9)
    return result


def repair_turns(
    template: MarkerState, frames: list[np.ndarray], taken: np.ndarray, triples: np.ndarray, symmetric: np.ndarray,
) -> tuple[np.ndarray, int, _Sightings]:
    """``taken`` with the labels of clusters that turned by a symmetry permuted back, how many
    repairs, and each cluster's last whole sighting at the window's end (``_Sightings.remembered``).

    Args:
        template: The markers at the template frame.
        frames: The window's points per frame after the template.
        taken: ``(N, M)`` the point each marker took per frame, -1 occluded.
        triples, symmetric: Rigid clusters and their symmetries (``rigid_triples``).
    """
    taken = taken.copy()
    sighting = _Sightings.at_template(template, triples)
    repairs = 0
    for m, points in enumerate(frames):
        current = taken_positions(points, taken[:, m])
        sighting.gap[sighting.gap >= 0] += 1
        full = ~np.isnan(current[triples]).any(axis=(1, 2))
        again = np.flatnonzero(full & (sighting.gap > 0))
        rotation = _turns(sighting.last[again], current[triples[again]], sighting.expected(again), IDENTITY)
        for k, best, turned in _symmetries_back(sighting, again, current[triples[again]], rotation, symmetric[again]):
            t = again[k]
            order = triples[t][PERMUTATIONS[best]]
            taken[triples[t], m:] = taken[order, m:]
            current[triples[t]] = current[order]
            rotation[2][k, 0] = turned
            repairs += 1
        sighting.seen_now(again, rotation[2][:, 0], current[triples], full)
    return taken, repairs, sighting


@dataclass
class _Sightings:
    """Per triple: its last full sighting ``(T, 3, 3)``, frames since (-1 never), its last
    step's rotation, and its turn rate (rad per frame, NaN unknown)."""

    last: np.ndarray
    gap: np.ndarray
    step: np.ndarray
    rate: np.ndarray

    @classmethod
    def at_template(cls, template: MarkerState, triples: np.ndarray) -> _Sightings:
        """The sightings a window starts from: a triple seen whole at the template is seen there,
        turning as its markers' velocities say; one that is not, at its last whole sighting
        the state remembers (``MarkerState.plate_*``, the same one for its three markers), so
        that a plate lost across a window's template is still read when it comes back."""
        seen = template.visible[triples].all(axis=1)
        age = template.plate_age[triples]
        remembered = ~seen & (age >= 0).all(axis=1) & (age == age[:, :1]).all(axis=1)
        gap = np.where(seen, 0, np.where(remembered, age[:, 0], -1))
        last = np.where(seen[:, None, None], template.position[triples], template.plate_position[triples])
        rate = np.where(seen, _turn_rate(template, triples), template.plate_rate[triples[:, 0]])
        return cls(np.where((gap >= 0)[:, None, None], last, np.nan), gap, np.tile(np.eye(3), (len(triples), 1, 1)),
                   np.where(gap >= 0, rate, np.nan))

    def remembered(self, state: MarkerState, triples: np.ndarray, frames: int) -> MarkerState:
        """``state`` (``frames`` after the template) with each triple's last whole sighting
        (``MarkerState.plate_*``); markers of no triple seen whole keep theirs, ``frames`` older."""
        position, rate = state.plate_position.copy(), state.plate_rate.copy()
        age = np.where(state.plate_age >= 0, state.plate_age + frames, -1)
        found = self.gap >= 0
        position[triples[found]] = self.last[found]
        age[triples[found]] = self.gap[found, None]
        rate[triples[found]] = self.rate[found, None]
        return replace(state, plate_position=position, plate_age=age, plate_rate=rate)

    def expected(self, rows: np.ndarray) -> np.ndarray:
        """``(K, 3, 3)`` the turn expected of ``rows`` since their last sighting: the last step
        again one frame on, none over a gap (a turn over a gap is no rate to go on)."""
        return np.where((self.gap[rows] == 1)[:, None, None], self.step[rows], np.eye(3))

    def seen_now(self, again: np.ndarray, rotation: np.ndarray, now: np.ndarray, full: np.ndarray) -> None:
        """Take ``now`` ``(T, 3, 3)`` as the last sighting of the ``full`` triples; ``again``, those
        seen before, turned by ``rotation`` ``(K, 3, 3)`` since."""
        turn = np.arccos(np.clip((np.trace(rotation, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
        self.step[again] = np.where((self.gap[again] == 1)[:, None, None], rotation, np.eye(3))
        self.rate[again] = turn / self.gap[again]
        self.last[full], self.gap[full] = now[full], 0


def _symmetries_back(sighting: _Sightings, again: np.ndarray, now: np.ndarray,
                     identity: tuple[np.ndarray, np.ndarray, np.ndarray],
                     symmetric: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """(row of ``again``, row of ``PERMUTATIONS``, its rotation) for each triple whose labels turned by a
    symmetry since its last sighting (module doc); ``identity`` is ``_turns`` of the labels as
    they are, ``symmetric`` the permutations each may take. Only labels that turned off the
    expected by the gap are tried permuted."""
    gap = sighting.gap[again]
    turn, fit = identity[0][:, 0], identity[1][:, 0]
    with np.errstate(invalid="ignore"):
        readable = (gap == 1) | (sighting.rate[again] * gap < np.radians(MIN_TURN_GAP_DEG))
    tried = np.flatnonzero(readable & (fit <= FIT_TOLERANCE_MM) & (turn >= np.radians(MIN_TURN_GAP_DEG)))
    if not len(tried):
        return []
    turns, fits, rotations = _turns(sighting.last[again[tried]], now[tried], sighting.expected(again[tried]), PERMUTATIONS)
    best = np.argmin(np.where((fits <= FIT_TOLERANCE_MM) & symmetric[tried], turns, np.inf), axis=1)
    gained = turns[:, 0] - turns[np.arange(len(tried)), best]
    kept = turns[np.arange(len(tried)), best]
    back = (best > 0) & (kept < np.radians(MIN_TURN_GAP_DEG)) & (gained >= np.radians(MIN_TURN_GAP_DEG))
    return [(int(tried[i]), int(best[i]), rotations[i, best[i]]) for i in np.flatnonzero(back)]


def _turn_rate(state: MarkerState, triples: np.ndarray) -> np.ndarray:
    """``(T,)`` an upper bound on each triple's turn per frame from its markers' velocities
    (|v_i - mean v| / |r_i|, r_i from the centroid), NaN where a velocity is unknown."""
    r = state.position[triples] - state.position[triples].mean(axis=1, keepdims=True)
    v = state.velocity[triples] - state.velocity[triples].mean(axis=1, keepdims=True)
    rate = (np.linalg.norm(v, axis=2) / np.maximum(np.linalg.norm(r, axis=2), 1e-9)).max(axis=1)
    return np.where(state.velocity_known[triples].all(axis=1), rate, np.nan)


def taken_positions(points: np.ndarray, took: np.ndarray) -> np.ndarray:
    """``(N, 3)`` the point each marker took in one frame (``took``: point index, -1 none),
    NaN where none."""
    result = np.full((len(took), 3), np.nan)
    result[took >= 0] = points[took[took >= 0]]
    return result


def _turns(before: np.ndarray, now: np.ndarray, expected: np.ndarray,
           orders: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per triple ``(K, 3, 3)`` and each of the P ``orders`` of ``now``'s rows: the angle (rad) of
    its Kabsch rotation off ``expected``, its RMS fit residual (mm), and the rotation ``(K, P, 3, 3)``."""
    a = before - axis_mean(before, 1, keepdims=True)
    moved = now[:, orders]  # (K, P, 3, 3)
    b = moved - axis_mean(moved, 2, keepdims=True)
    u, _, vt = np.linalg.svd(np.einsum("tki,tpkj->tpij", a, b))
    sign = np.sign(np.linalg.det(np.einsum("tpji,tpkj->tpik", vt, u)))
    d = np.tile(np.eye(3), sign.shape + (1, 1))
    d[..., 2, 2] = np.where(sign == 0, 1.0, sign)
    rotation = np.einsum("tpji,tpjk,tplk->tpil", vt, d, u)  # R = V D U^T, b ~ R a
    fitted = np.einsum("tpij,tkj->tpki", rotation, a)
    fit = np.sqrt(axis_mean(((fitted - b) ** 2).sum(axis=3), 2))
    off = np.einsum("tpij,tkj->tpik", rotation, expected)  # R_pi R_hat^T
    cosine = np.clip((np.trace(off, axis1=2, axis2=3) - 1.0) / 2.0, -1.0, 1.0)
    return np.arccos(cosine), fit, rotation
