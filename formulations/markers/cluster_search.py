"""Lost rigid clusters found again by their shape alone, whatever pose they come back in.

``realign_lost`` registers a lost group to the cloud by ICP from two translations: it finds
a subject who comes back in the posture and heading it left in. The wheelchair basketball
sprint (kineticstoolkit, from frame 1632) loses every marker at frame 2181; its upper arm is
in view again on and off soon after, and the rest from frame 2880 a metre away, the chair
turned by about 140 degrees and the wheel turned on it: no one rigid fit of the whole group
is within 26 mm of them. Its markers sit in plates of four (chair, wheel, upper arm,
forearm), and a plate's distances do not depend on pose.

So each cluster of three or more lost markers rigid with each other (learned sd of every
pair at most ``max_sd_mm``, a clique of the neighbour tables) is looked for by its
three markers spread widest, a, b, c, and again by the widest three without each of them (a
member may be absent when its plate comes back: the sprint's upper arm came back into view
for 700 frames without the elbow marker of its cluster): every triple (i, j, l) of free
points with

    | ||x_i - x_j|| - d_ab | <= tol,  | ||x_i - x_l|| - d_ac | <= tol,  | ||x_j - x_l|| - d_bc | <= tol,

tol = 3 times the cluster's largest learned sd plus ``noise_mm``, places the whole cluster by
the Kabsch fit of its shape onto the triple. The shape is the members' learned mean distances
d_mj laid out by classical MDS (``learned_shape``), not their last-seen positions: the
sprint's chair was last seen with one marker on another's point (two markers 342 mm apart
against 211), and every fit of that shape missed. Distances do not tell a shape from its
mirror image, so both images are fitted; the wrong one leaves the fourth marker off its point.

The fit that brings the most members within ``tol`` of a free point is taken when it
explains ``min_members`` of them or more and no other fit explains as many with another
point for any member: a symmetric plate (a square) fits several ways and is left where it
was, and so are two lost clusters of one shape that both fit the same points.

Three members are a weaker sighting: in a crowded cloud some triangle of free points nearly
always matches three distances (the sprint's forearm, three markers rigid with each other,
fitted the wheel's points, and the head's three the wheel's and the sync marker's, when
clusters of three were placed by their last-seen positions). Yet the sprint's plates come
back into a sparse volume three at a time, six points in view and nothing labeled: 825 of
the 1,414 plate samples the take lost (wrong or unlabeled) had three of their plate's
markers in view. So a cluster (of three, or of four with one absent) is placed by three
members only when that reading is the only one of its fits (as for four) and no other lost
cluster fits any of its points by three or more members, nor a placement of four holds one:
a lookalike, or a triangle two clusters share, leaves both where they were. And only where
most free points are some cluster's fit's: in a crowd (a whole subject back in view,
stretched past its plates' fits, or ghosts) a triangle of three distances found once is as
likely chance (CMU 85_02 back 1.5 m away, 30 % larger: the head's three back markers matched
one triangle of its 41 points, a wrong one). A member no point explains (a marker absent
when its plate comes back) keeps its prediction. The members explained have their
predictions moved onto their points; the window then decides what they take.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.distance import cdist

from formulations.markers.mirror import LearnedPairs
from formulations.markers.reacquire import REACQUISITION, free_points
from formulations.markers.rigid import rigid_transform
from formulations.markers.state import MarkerState


@dataclass(frozen=True)
class ClusterSearch:
    """Which lost clusters are looked for by shape, and how closely they must fit.

    Attributes:
        max_sd_mm: A pair whose learned distance sd is above this is not one plate.
        noise_mm: Added to a cluster's tolerance: the noise of two points.
        min_members: A fit explaining this many members places its cluster unless another cluster's
            placement holds one of its points; one explaining three only where it is unambiguous
            (three distances nearly always match some triangle of a crowded cloud: module doc).
    """

    max_sd_mm: float = 3.0
    noise_mm: float = 3.0
    min_members: int = 4


CLUSTER_SEARCH = ClusterSearch()
TRIANGLE = 3  # members that place a cluster at all: three points fix a rigid fit


def search_lost_clusters(
    guess: np.ndarray, state: MarkerState, lost: np.ndarray, points: np.ndarray,
    settings: ClusterSearch = CLUSTER_SEARCH,
) -> np.ndarray:
    """``(N, 3)`` predictions with each lost cluster found by its shape moved onto its points
    (those no seen marker's prediction claims, ``Reacquisition.claim_mm``)."""
    points = free_points(points, guess[state.visible], REACQUISITION.claim_mm)
    if len(points) < TRIANGLE:
        return guess
    learned = LearnedPairs.of(state)
    d_points = cdist(points, points)  # once for every cluster's triples
    sightings = [_sighting(cluster, learned, points, d_points, settings) for cluster in rigid_clusters(learned, lost, settings)]
    # Markers unseen but not yet lost are not searched, but their points are free as well: a
    # triangle of theirs that matches leaves a sighting by three undecided (plates need none).
    rivals = [_sighting(cluster, learned, points, d_points, settings)
              for cluster in rigid_clusters(learned, ~state.visible & ~lost, settings)
              ] if any(s.explained == TRIANGLE for s in sightings) else []
    found = guess.copy()
    for sighting in _unambiguous(sightings, rivals, settings.min_members, len(points)):
        kept = sighting.reading >= 0
        found[sighting.cluster[kept]] = points[sighting.reading[kept]]
    return found


@dataclass(frozen=True)
class _Sighting:
    """A rigid cluster's best fit: the point each member is on (-1: none), how many it
    explains (0: no one reading), and every point a fit explaining three or more touches."""

    cluster: NDArray[np.int64]
    reading: NDArray[np.intp]
    explained: int
    touched: frozenset[int]

    @property
    def on(self) -> set[int]:
        """The points the best fit puts members on."""
        return set(self.reading[self.reading >= 0].tolist())


def _sighting(
    cluster: NDArray[np.int64], learned: LearnedPairs, points: np.ndarray, d_points: np.ndarray, settings: ClusterSearch,
) -> _Sighting:
    inside = np.ix_(cluster, cluster)
    tol = 3 * np.sqrt(np.where(np.eye(len(cluster), dtype=bool), 0.0, learned.var[inside]).max()) + settings.noise_mm
    reading, explained, touched = _placed(learned_shape(learned.mean[inside]), points, d_points, tol)
    return _Sighting(cluster, reading, explained, touched)


def _unambiguous(sightings: list[_Sighting], rivals: list[_Sighting], min_members: int, n_points: int) -> list[_Sighting]:
    """The sightings taken (module doc): of ``min_members`` or more, those sharing no point
    with another such; of three, those whose points no other cluster's fit touches, lost or
    only unseen (``rivals``), where most of the ``n_points`` free points are some fit's."""
    plates = [s for s in sightings if s.explained >= min_members]
    # two plates on one point: one of them is a lookalike, and nothing says which
    taken = [s for s in plates if not any(o.on & s.on for o in plates if o is not s)]
    if 2 * len(frozenset().union(*(s.touched for s in sightings + rivals))) <= n_points:
        return taken  # a crowd: one triangle of it that matches may be chance
    held = set().union(*(s.on for s in plates))
    for s in sightings:
        if s.explained == TRIANGLE and not s.on & held and not any(s.on & o.touched for o in sightings + rivals if o is not s):
            taken.append(s)
    return taken


def rigid_clusters(learned: LearnedPairs, lost: np.ndarray, settings: ClusterSearch = CLUSTER_SEARCH) -> list[NDArray[np.int64]]:
    """Cliques of lost markers whose every pair is learned rigid (in either marker's table),
    greedily from each lost marker in turn (a marker joins one cluster): cliques of
    ``min_members`` or more first, then of three from the markers left."""
    rigid = learned.var <= settings.max_sd_mm**2
    rigid = (rigid | rigid.T) & lost[:, None] & lost[None]
    np.fill_diagonal(rigid, False)
    free, clusters = lost.copy(), []
    for least in (settings.min_members, TRIANGLE):
        for m in np.flatnonzero(free):
            if not free[m]:
                continue
            members = [m]
            for j in np.flatnonzero(rigid[m] & free):
                if rigid[j, members].all():
                    members.append(j)
            if len(members) >= least:
                clusters.append(np.array(members))
                free[members] = False
    return clusters


def learned_shape(mean: np.ndarray) -> np.ndarray:
    """``(k, 3)`` the members placed by classical MDS of their ``(k, k)`` learned mean distances
    (either marker's, averaged where both keep the pair; any pose, one of its two mirror
    images): a member last seen on another's point would bend the last-seen positions, not
    the means learned over the take."""
    k = len(mean)
    apart = np.where(np.eye(k, dtype=bool), 0.0, (mean + mean.T) / 2)
    centre = np.eye(k) - 1.0 / k
    value, vector = np.linalg.eigh(-0.5 * centre @ apart**2 @ centre)
    top = np.argsort(value)[::-1][:3]
    shape: np.ndarray = vector[:, top] * np.sqrt(np.maximum(value[top], 0.0))
    return shape


def _placed(
    shape: np.ndarray, points: np.ndarray, d_points: np.ndarray, tol: float,
) -> tuple[NDArray[np.intp], int, frozenset[int]]:
    """The point each member of ``shape`` is on in the one fit that explains the most of
    them (-1: a member it does not explain, module doc), how many that is (0 when another
    fit explains as many with other points), and the points any fit explaining three or
    more touches; ``d_points`` the points' distances."""
    none = np.full(len(shape), -1, dtype=np.intp)
    d_shape = cdist(shape, shape)
    fits = [f for triple in _spanning_triples(shape) if (f := _fits(shape, d_shape, points, d_points, triple, tol)) is not None]
    if not fits:
        return none, 0, frozenset()
    moved = np.concatenate(fits)
    distance = cdist(moved.reshape(-1, 3), points).reshape(len(moved), len(shape), len(points))
    nearest, within = distance.argmin(axis=2), distance.min(axis=2) <= tol
    explained = within.sum(axis=1)
    readings = np.where(within, nearest, -1)
    touching = readings[explained >= TRIANGLE]
    touched = frozenset(touching[touching >= 0].tolist())
    tops = np.flatnonzero(explained == explained.max())
    if len({tuple(readings[t]) for t in tops}) > 1:  # the plate fits another way as well: its symmetry, or a lookalike
        return none, 0, touched
    return readings[tops[0]].astype(np.intp), int(explained.max()), touched


def _fits(
    shape: np.ndarray, d_shape: np.ndarray, points: np.ndarray, d_points: np.ndarray, triple: tuple[int, int, int],
    tol: float,
) -> np.ndarray | None:
    """``(2T, k, 3)`` ``shape`` and its mirror image moved by the Kabsch fit of members
    ``triple`` onto each of the T triples of points with their three distances; None if none."""
    a, b, c = triple
    near = [np.abs(d_points - d_shape[u, v]) <= tol for u, v in ((a, b), (a, c), (b, c))]
    i, j = np.nonzero(near[0])
    pair, r = np.nonzero(near[1][i] & near[2][j])
    if not len(pair):
        return None
    triples = np.column_stack([i[pair], j[pair], r])
    target = np.tile(points[triples], (2, 1, 1))  # (2T, 3, 3): each triple, each mirror image
    mirror = shape * np.array([1.0, 1.0, -1.0])
    shapes = np.repeat(np.stack([shape, mirror]), len(triples), axis=0)  # (2T, k, 3)
    rotation, c_s, c_t = rigid_transform(shapes[:, [a, b, c]], target, np.ones(target.shape[:2]))
    moved: np.ndarray = np.einsum("tij,tkj->tki", rotation, shapes - c_s[:, None]) + c_t[:, None]
    return moved


def _spanning_triples(shape: np.ndarray) -> list[tuple[int, int, int]]:
    """The three members spanning the largest triangle (the best-conditioned fit), and for each
    of them the widest three without it: a member absent when its plate comes back (the
    basket sprint's elbow marker, in the upper arm's cluster) must not keep the plate unfound."""
    triples = np.array(list(combinations(range(len(shape)), 3)))
    u, v, w = shape[triples].transpose(1, 0, 2)
    area = np.linalg.norm(np.cross(v - u, w - u), axis=1)
    widest = triples[area.argmax()]
    chosen = [widest] + [triples[np.where((triples != m).all(axis=1), area, -1.0).argmax()] for m in widest]
    return [(int(a), int(b), int(c)) for a, b, c in chosen]
