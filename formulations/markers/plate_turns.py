"""Recovery over a whole labeled take: a plate of three markers with equal sides read
exchanged, given back by how far the plate turned.

A plate with equal sides (a wheelchair racer's 43 mm triangles) keeps every distance under any
exchange of its labels, so every repair that judges by distances (``take_exchange``,
``take_rotation``, the window's shape term) is blind to it. How far the plate turned is not:
for a frame t labeling all three markers, X_t their points in label order, and a reading
sigma (label i takes the point the labels gave sigma(i)), the plate turns between full
frames s < t by

    theta(s, t) = angle(R*),  R* = argmin over R in SO(3) of sum_i |R x_s,i - x_t,i|^2

(both centred; Kabsch). A reading that exchanges two labels adds a half turn (the triangle
turned over) and one that takes them round a third of a turn: at least 120 degrees on top of
what the segment turned.

The take's labels say how far the plate turns in d frames: the ``QUANTILE`` of theta over the
pairs of full frames d apart. A pair d apart tells readings apart only where that stays under
``TURN_LIMIT``, half the least turn an exchange adds; there it costs theta, farther apart
nothing. The readings over the full frames are the cheapest path (Viterbi): six states, the
labeled first frame's own to start (frame 0 is never read otherwise), a change of reading
costing ``CHANGE_DEGREES``. A step
too long to tell leaves the reading after it free: the frames it links are read as most of
them are labeled (``OTHER_READING`` a frame breaks that tie; nothing ties them to the first
frame). Between two full frames read differently the change goes where the labels' own steps
from the frame before are longest against the steps the change makes (a label's track jumping
where the changed reading continues it; never cutting a track the labels hold smoothly), the
latest of equals.

A run read so is given back unless the plate's witnesses deny it
(``witness_costs.witnesses_deny``: the markers rigid with it favour the labels by the bar a
take-wide permutation must clear). The plate alone cannot tell a turn of 113 degrees under a
34-frame loss from the 49 another reading turns plus a change (HDM05's wrist, seed 0: read
taken round over 360 frames, 1,142 labels lost); its elbow and forearm markers can. Measured
(lp-l1, 2026-12-06, against no witnesses): on racing's labels before the take-wide repairs
(seeds 0-2, five conditions, 235 turns) the bar denies 10 turns, all wrong, and no right one;
seed-0 accuracy matrix 2 rows up and 1 down of 85 (racing default 95.25 -> 93.29 %: the second
pass learns from the repaired labels), racing and HDM05 at seeds 1-2 2 up and 1 down of 20.

It runs after the take-wide exchanges, rotations and half turns (``service.labeling.exchanged``).
Measured (lp-l1, 600 frames): the wheelchair racing take's 15 rows of seeds 0-2, 13 higher
and 2 lower (seed 0 at 2 mm 86.76 -> 85.65 %, at 4 mm 61.85 -> 61.75), default 90.73 -> 93.57 %
at seed 0; every other take of the seed-0 accuracy matrix the same to the label
(``docs/how-a-window-is-solved.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations, permutations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from formulations.markers.noise import MAD_TO_SIGMA
from formulations.markers.pair_spread import PairSpreads
from formulations.markers.rigid import rigid_transform
from formulations.markers.witness_costs import witnesses_deny

Array = NDArray[np.float64]

TURN_LIMIT = 60.0  # degrees: half the least turn (a third of a turn) an exchange adds
QUANTILE = 0.9  # of the plate's turns over d frames that must stay under the limit
MIN_PAIRS = 10  # pairs of full frames d apart to trust that quantile
PAIRS_PER_LAG = 400  # pairs sampled per lag: enough for a quantile, bounded on long takes
EQUAL_SHARE = 0.05  # sides within 5 %: racing's plates 1-3 %, a head's four markers 8-20 %
SIDE_SDS = 5.0  # a side this many robust sd off its median is not the plate's
MIN_SIDE_SD = 0.01  # of the side: a floor, so that a noiseless take's rounding is not an outlier
CHANGE_DEGREES = 30.0  # a change of reading: well under the 120 degrees an exchange adds
OTHER_READING = 1e-3  # degrees a full frame read otherwise than labeled: breaks ties only
READINGS = [np.array(p) for p in permutations(range(3))]
# readings p before and q after turn the plate as the labels' X_s against X_t[q[p^-1]]: its index
RELATIVE = np.array([[next(i for i, r in enumerate(READINGS) if np.array_equal(r, q[np.argsort(p)])) for q in READINGS]
                     for p in READINGS])


@dataclass(frozen=True)
class PlateTurn:
    """Over frames [start, stop) each of ``markers`` takes the labels of the next one (the last
    the first's): two markers exchanged, or three taken round."""

    markers: tuple[int, ...]
    start: int
    stop: int


def turn_angles(a: Array, b: Array) -> Array:
    """Degrees of the proper rotation best taking each plate ``a[k]`` ``(3, 3)`` onto ``b[k]``
    (``rigid.rigid_transform``, every corner weighed alike)."""
    turn, _, _ = rigid_transform(a, b, np.ones(a.shape[:2]))
    cosine = (np.trace(turn, axis1=-2, axis2=-1) - 1) / 2
    return np.asarray(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))


def telling_lag(points: Array, full: NDArray[np.int64]) -> int:
    """The largest d such that the plate's turns over every lag up to d stay under ``TURN_LIMIT``
    at ``QUANTILE`` (module doc); 0 when not even one frame does. Each pair's turn is the least
    over the readings: the labels' own would count their exchanges as turns, and a turn under
    the limit is the least. No more than the longest step between full frames."""
    is_full = np.zeros(len(points), bool)
    is_full[full] = True
    lag, longest = 0, int(np.diff(full).max())
    while lag < longest:
        start = full[full + lag + 1 < len(points)]
        start = start[is_full[start + lag + 1]]
        if len(start) < MIN_PAIRS:
            return lag
        start = start[np.linspace(0, len(start) - 1, min(len(start), PAIRS_PER_LAG)).astype(int)]
        least = np.min([turn_angles(points[start], points[start + lag + 1][:, r]) for r in READINGS], axis=0)
        if np.quantile(least, QUANTILE) > TURN_LIMIT:
            return lag
        lag += 1
    return lag


def plate_readings(points: Array) -> NDArray[np.int64]:
    """Per frame the reading (an index into ``READINGS``) of one plate's labeled ``points``
    ``(T, 3, 3)`` (NaN unlabeled) that turns it least (module doc); 0, the labels' own, where
    nothing tells."""
    full = _full_frames(points)
    reading = np.zeros(len(points), dtype=np.int64)
    lag = telling_lag(points, full) if len(full) > 1 else 0
    if lag == 0:
        return reading
    at_full = _cheapest_path(points, full, lag)
    if at_full[0]:  # the labeled first frame keeps its labels: the change goes after it
        reading[_change_frame(points, 0, full[0], READINGS[0], READINGS[at_full[0]]):full[0]] = at_full[0]
    for k in range(len(full) - 1):
        was, becomes = at_full[k], at_full[k + 1]
        change = full[k + 1] if was == becomes else _change_frame(points, full[k], full[k + 1], READINGS[was],
                                                                  READINGS[becomes])
        reading[full[k]:change] = was
        reading[change:full[k + 1]] = becomes
    reading[full[-1]:] = at_full[-1]
    return reading


def _full_frames(points: Array) -> NDArray[np.int64]:
    """The frames labeling all three markers of the plate with its own sides: each within
    ``SIDE_SDS`` robust sd of its median over the take (a ghost or a neighbour's point taken
    for one of them makes a triangle whose turn means nothing)."""
    sides = np.stack([np.linalg.norm(points[:, i] - points[:, j], axis=1) for i, j in combinations(range(3), 2)], axis=1)
    labeled = np.isfinite(sides).all(axis=1)
    if not labeled.any():
        return np.flatnonzero(labeled)
    off = np.abs(sides - np.median(sides[labeled], axis=0))
    sd = np.maximum(MAD_TO_SIGMA * np.median(off[labeled], axis=0), MIN_SIDE_SD * np.median(sides[labeled]))
    with np.errstate(invalid="ignore"):
        return np.flatnonzero(labeled & (off <= SIDE_SDS * sd).all(axis=1))


def _cheapest_path(points: Array, full: NDArray[np.int64], lag: int) -> NDArray[np.int64]:
    """Viterbi over the full frames: the reading at each (indices into ``READINGS``). A step
    longer than ``lag`` tells nothing: the reading after it is free (module doc)."""
    n = len(READINGS)
    change = CHANGE_DEGREES * (1 - np.eye(n))
    other = OTHER_READING * (np.arange(n) != 0)
    told = np.diff(full) <= lag
    turns = np.zeros((len(full) - 1, n))
    turns[told] = np.stack([turn_angles(points[full[:-1][told]], points[full[1:][told]][:, r]) for r in READINGS], axis=1)
    cost = np.where(np.arange(n) == 0, 0.0, np.inf if full[0] == 0 else 0.0) + other  # the labeled first frame's own
    back = np.zeros((len(full), n), dtype=np.int64)
    for k in range(1, len(full)):
        total = cost[:, None] + (turns[k - 1][RELATIVE] + change if told[k - 1] else np.zeros((n, n)))
        back[k] = np.argmin(total, axis=0)
        cost = total[back[k], np.arange(n)] + other
    path = np.zeros(len(full), dtype=np.int64)
    path[-1] = int(np.argmin(cost))
    for k in range(len(full) - 1, 0, -1):
        path[k - 1] = back[k, path[k]]
    return path


def _change_frame(points: Array, before: int, after: int, was: NDArray[np.int64], becomes: NDArray[np.int64]) -> int:
    """The frame in (before, after] where the reading ``was`` becomes ``becomes``: where the
    labels' own steps are longest against the steps the change makes (module doc); the latest
    of equals. Every other step is the same under either reading: a reading moves whole tracks."""
    frames = np.arange(before + 1, after + 1)
    last, now = points[frames - 1], points[frames]
    own = np.nansum(np.linalg.norm(now - last, axis=2), axis=1)
    changed = np.nansum(np.linalg.norm(now[:, becomes] - last[:, was], axis=2), axis=1)
    gain = own - changed
    return int(frames[::-1][np.argmax(gain[::-1])])


def equal_plates(positions: Array, first: Array) -> list[tuple[int, int, int]]:
    """The plates of labeled ``positions`` ``(T, N, 3)`` (NaN unlabeled): three markers each
    among the other two's nearest in labeled frame ``first`` ``(N, 3)``, whose median sides
    over the take differ by at most ``EQUAL_SHARE`` of their mean and keep their lengths as
    rigid pairs do (``PairSpreads.rigid``: a neck marker and two at the back of the head may
    have equal sides, but a turn of the head is no turn of a plate)."""
    plates, spreads = [], PairSpreads(positions)
    for plate in mutual_triples(first):
        sides = [np.nanmedian(np.linalg.norm(positions[:, i] - positions[:, j], axis=1)) for i, j in combinations(plate, 2)]
        rigid = spreads.rigid(list(plate), list(plate))
        if max(sides) - min(sides) <= EQUAL_SHARE * float(np.mean(sides)) and rigid[np.triu_indices(3, 1)].all():
            plates.append(plate)
    return plates


def mutual_triples(frame: Array) -> list[tuple[int, int, int]]:
    """Triples of labeled markers in ``frame`` ``(N, 3)`` (NaN rows unlabeled), each marker's
    two nearest being the other two."""
    seen = np.flatnonzero(np.isfinite(frame).all(axis=1))
    if len(seen) < 3:
        return []
    _, nearest = cKDTree(frame[seen]).query(frame[seen], k=3)
    near = {int(m): {int(j) for j in seen[row[1:]]} for m, row in zip(seen, nearest, strict=True)}
    # each of the three names the other two: a, b of m's, and m with the other of a's and b's
    triples = {tuple(sorted((m, a, b))) for m, (a, b) in ((m, sorted(pair)) for m, pair in near.items())
               if near[a] == {m, b} and near[b] == {m, a}}
    return sorted(triples)  # type: ignore[arg-type]


def plate_turns(positions: Array, first: Array, neighbours: NDArray[np.int64]) -> list[PlateTurn]:
    """The runs over which each plate's labels are read otherwise (module doc), from labeled
    ``positions`` ``(T, N, 3)`` (NaN unlabeled), the labeled ``first`` frame and each marker's
    ``neighbours`` there, as exchanges or rotations to give back; a run the plate's rigid
    witnesses deny (``witness_costs.witnesses_deny``) is not."""
    turns, spreads = [], PairSpreads(positions)
    for plate in equal_plates(positions, first):
        reading = plate_readings(positions[:, list(plate)])
        edges = np.flatnonzero(np.diff(np.r_[0, reading, 0]))
        for start, stop in zip(edges[:-1], edges[1:], strict=True):
            if not reading[start]:
                continue
            turn = PlateTurn(_cycle(plate, READINGS[reading[start]]), int(start), int(stop))
            markers = list(turn.markers)
            if not witnesses_deny(positions, first, neighbours, spreads, markers, markers[1:] + markers[:1],
                                  list(plate), slice(start, stop)):
                turns.append(turn)
    return turns


def _cycle(plate: tuple[int, int, int], reading: NDArray[np.int64]) -> tuple[int, ...]:
    """``reading`` (label i takes what label reading[i] held) as a cycle of marker indices."""
    moved = [i for i in range(3) if reading[i] != i]
    cycle = [moved[0]]
    while reading[cycle[-1]] != cycle[0]:
        cycle.append(int(reading[cycle[-1]]))
    return tuple(plate[i] for i in cycle)
