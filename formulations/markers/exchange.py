"""Recovery: give exchanged markers back their tracks at a window's template.

Once markers have swapped tracks (two exchanged, three passed round, or one holding a
lost neighbour's point while its own goes unclaimed), every later window inherits it: a
step back costs large jumps and nothing in one window pays for them. What an exchange
breaks is the shape: each marker sits where its learned neighbour distances do not fit.
With D[m, p] the shape deviation of marker m placed at position r_p,

    D[m, p] = sum_j a_mj min(| ||r_p - r_j|| - dbar_mj |, c) / sum_j a_mj,

a_mj = 1 / (var_mj + 1) over m's visible neighbours j (``MarkerState``) but the one at r_p
itself (in an exchange that is the partner, which moves too), the tracks at the
template (the visible markers' points and the points nobody took) are reassigned by the
assignment minimising sum_m D[m, track(m)], where a marker may hold no track at cost
``NONE_MM``. Each connected change (markers linked by the tracks they give and take) is
kept when it gains ``EXCHANGE_GAIN_MM`` per marker and at least halves its deviation.
The distance statistics adapt to a swapped track over about 1 / rate = 33 frames, so the
test runs at every template, before they have.

The gain guards right labels: skin motion and noise alone move the deviations of markers a
few cm apart by a few mm. A label already judged doubtful by other evidence (``confidence``
c_m: the window's margins and the shape from when it was last trusted) needs less guarding:
a change must gain ``EXCHANGE_GAIN_MM`` times the sum of its markers' c_m, the gain a sure
change needs weighed by the chance that the labels it undoes are right. RTOE and RMT5, 5 cm
apart on CMU 85_02's forefoot, came back exchanged with deviations 30-34 mm against 15-18 mm
swapped back (gain 15-19 mm, under the 40 mm two sure markers need), both at c = 0.00-0.01,
for the 225 frames to the end. Accuracy matrix (600 frames, seed 0, five conditions, lp-l1):
validation half 96.28 -> 96.42 %, tuning half 95.58 -> 95.79 % (docs/confidence.md). Waiving
the gain for doubtful markers outright also moved a wrist marker at c = 0.66 alone onto a
free point at the tennis serve (96.2 -> 94.1 %).

A marker unseen at the template that would take a free point is re-acquired on its shape
alone, however far from its prediction; a ghost near the body can fit that shape as well
as the marker's own point. So an unseen marker takes only a free point that goes on: one
the next frame has a point near (``continued_points``, within the one-frame reach of the
unnamed tracks: the 90th percentile of the seen markers' speeds plus 5 sd of their motion
residual). On the validation take 03_rolling (default condition, seed 0) LL_HME, hidden,
was put on a ghost 389 mm from its prediction at template 152 (the next frame's nearest
point 207 mm from it), and the left arm's markers then took one another's points: 91.14 ->
97.11 %. Of the 22 such moves there and on the tennis serve (default, seed 0), the 9 right
ones were continued within 4-104 mm and none of the 12 onto ghosts within 79 mm (one more
took another marker's point, continued). A visible marker's own free point is taken
back either way. Accuracy matrix, lp-l1, 600 frames: seed 0 (85 rows) 97.209 -> 97.338 %,
swaps 1,645 -> 1,584; seeds 1-2 (170 rows) 97.119 -> 97.211 %; ``unnamed-3`` seeds 0-2
96.214 -> 96.130 %. Barring unseen markers from free points outright, or allowing only
points inside their gate, was tried and lost more than it gained (docs/how-a-window-is-solved.md, Recovery).

Nor does an unseen marker take a free point whose track was seen beside it
(``coexistence``): a track followed back to the frame the marker was last seen in, and
somewhere else then, is another object, however well it fits the marker's distances.

Nor does a marker take a free point another lost marker claims (``claimed_from``), unless it
claims the point too or is carried less than ``FAR_RATIO`` (3, the hand-over repair's) times
as far from it as the claimant. The claim is the one the shape re-acquisition honours
(``shape_reacquire.point_claims``: carried within 30 mm of the point, and the point inside
the marker's own chi-square shape gate). Distances to neighbours across a joint cannot tell
apart two markers a few cm apart: on 03_rolling (default condition, seed 0) the left ulnar
styloid, lost for 26 frames and carried 75 mm from the point, was handed at template 323 the
point of the radial styloid, lost one frame and carried 6 mm from it (deviations 11.0
against 12.9 mm: pronation bends the radius's distances to the epicondyles); the two traded
the point from window to window for 190 frames (98.63 -> 99.44 % with the claim). A marker
that claims the point too is not barred: in the wheelchair racing take's clusters, 30 mm
across, every lost mate is carried within 30 mm of every mate's point, and barring all but
the claimants kept right repairs from being made (racing with ghosts 86.21 -> 85.21 %,
86.59 % as it is). Nor is one carried nearly as near: two right metacarpals of the real
03_rolling, lost and carried 23-38 mm from both their points, were handed each other's
points at frame 2215 when the one 38 mm from its own (no claim) was barred by the other's
claim at 25 mm.

Each marker is judged above against its neighbours where they are now, the partner left
out; a change that also moves the partner can break their own distance, which that test
never sees. So each change that passes is judged again as a whole: with every marker where
the changes put it, the sum over the change's markers of each one's deviation at its own
track (``NONE_MM`` for one left with none) must fall. In CMU 85_02 in Pose2Sim's 4-camera
rig, RWRA, unseen for 21 frames, was handed RWRB's point while RWRB took a second
triangulation of itself 10 mm away: two markers 60 mm apart made 10 mm apart, and the next
window kept RWRA there for 19 frames (the camera scenario's fill 27.8 -> 15.2 mm RMSE with
the check, accuracy 99.73 -> 99.82 %). Accuracy matrix (lp-l1, seed 0, 85 rows): 97.003 ->
97.016 %, 5 rows higher and 1 lower, swaps 1,726 -> 1,721.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial.distance import cdist

from formulations.markers.lengths import lengths
from formulations.markers.shape_reacquire import point_claims
from formulations.markers.state import MarkerState
from formulations.markers.take_handover import FAR_RATIO

SHAPE_CAP_MM = 50.0  # c, as the shape term of ``cloud_candidates``
EXCHANGE_GAIN_MM = 20.0  # a change must explain the shape by this much per marker (weighted mean mm) ...
EXCHANGE_RATIO = 0.5  # ... and halve the deviation of the markers it moves
NONE_MM = 40.0  # holding no track: worse than any fitting track, better than a wrong one
_TRACK_FIELDS = (
    "position", "velocity", "velocity_known", "unseen", "streak", "anchor", "anchor_neighbours", "anchor_valid",
    "anchor_carried", "seen_at",
)


def shape_deviations(state: MarkerState, positions: np.ndarray) -> np.ndarray:
    """``(N, P)`` D[m, p] (module doc) for candidate positions ``(P, 3)``; inf for markers with
    no visible neighbour (nothing to judge them by)."""
    return _deviations_at(state, lengths(positions[None, :, None] - state.position[state.neighbours][:, None]))


def _deviations_at(state: MarkerState, distance: np.ndarray) -> np.ndarray:
    """``(N, P)`` D[m, p] from ``distance`` ``(N, P, K)``, ||r_p - r_j|| to each of m's neighbours j."""
    # A neighbour that holds the position itself says nothing of it: in an exchange it is the
    # partner, which moves too (their mutual distance is the same either way).
    weight = (state.visible[state.neighbours] / (state.distance_var + 1.0))[:, None] * (distance > 1e-6)  # (N, P, K)
    deviation = np.minimum(np.abs(distance - state.distance_mean[:, None]), SHAPE_CAP_MM)
    total = weight.sum(axis=2)
    shape: np.ndarray = np.einsum("npk,npk->np", weight, deviation) / np.maximum(total, 1e-12)
    return np.where(total > 0, shape, np.inf)


def repair_exchanges(
    state: MarkerState, unclaimed: np.ndarray, confidence: np.ndarray | None = None,
    continued: np.ndarray | None = None, coexisting: np.ndarray | None = None,
) -> tuple[MarkerState, int]:
    """The state with exchanged tracks given back (module doc), and how many markers moved.

    Args:
        state: The markers at the template frame.
        unclaimed: ``(U, 3)`` points of the template frame no marker took.
        confidence: ``(N,)`` probability that each marker's label is right; None: all sure.
        continued: ``(U,)`` the unclaimed points a point of the next frame continues
            (``continued_points``); an unseen marker takes no other (module doc). None: any.
        coexisting: ``(N, U)`` True where an unclaimed point's track was seen beside the
            marker (``coexistence.coexisted``): that marker does not take it. None: none was.
    """
    n, visible = len(state.position), np.flatnonzero(state.visible)
    tracks = np.concatenate([state.position[visible], unclaimed.reshape(-1, 3)])
    if len(visible) < 2 or len(tracks) == 0:
        return state, 0
    shape = shape_deviations(state, tracks)
    cost = np.hstack([np.where(np.isfinite(shape), shape, 1e6), np.full((n, n), 1e6)])
    if continued is not None:  # an unseen marker is re-acquired on a track, not on a flash
        cost[np.ix_(~state.visible, len(visible) + np.flatnonzero(~continued))] = 1e6
    if coexisting is not None:
        cost[:, len(visible):len(tracks)][coexisting] = 1e6
    cost[:, len(visible):len(tracks)][claimed_from(state, unclaimed.reshape(-1, 3))] = 1e6
    np.fill_diagonal(cost[:, len(tracks):], NONE_MM)
    rows, cols = linear_sum_assignment(cost)
    before = np.full(n, -1)
    before[visible] = np.arange(len(visible))
    after = np.where(cols < len(tracks), cols, -1)[np.argsort(rows)]
    moved = np.flatnonzero(after != before)
    if len(moved) == 0:
        return state, 0
    sure = np.ones(n) if confidence is None else np.clip(confidence, 0.0, 1.0)
    change = _changes(before, after, moved, len(tracks))
    accept = _accepted(shape, before, after, moved, change, sure)
    if accept.any():
        accept &= _whole_change_fits(state, reassigned(state, visible, tracks, np.where(accept, after, before)), change, accept)
    if not accept.any():
        return state, 0
    return reassigned(state, visible, tracks, np.where(accept, after, before)), int(accept.sum())


def claimed_from(state: MarkerState, unclaimed: np.ndarray) -> np.ndarray:
    """``(N, U)`` markers barred from free points another lost marker claims (module doc): one
    that claims the point too is not, nor one carried less than ``FAR_RATIO`` times as far
    from it as the nearest claimant."""
    claims = point_claims(state.position, state, unclaimed)
    apart = lengths(unclaimed[None] - state.position[:, None])  # (N, U)
    claimant = np.where(claims, apart, np.inf).min(axis=0)  # (U,) inf where none claims
    barred: np.ndarray = ~claims & (apart >= FAR_RATIO * claimant[None])
    return barred


def continued_points(points: np.ndarray, following: np.ndarray, reach: float) -> np.ndarray:
    """``(P,)`` whether the frame after has a point within ``reach`` of each of ``points``
    (``(P, 3)``; ``following`` ``(Q, 3)``): a track goes on, a one-frame flash does not."""
    if not len(points) or not len(following):
        return np.zeros(len(points), bool)
    near: np.ndarray = cdist(points, following).min(axis=1) <= reach
    return near


def _changes(before: np.ndarray, after: np.ndarray, moved: np.ndarray, n_tracks: int) -> np.ndarray:
    """``(N,)`` the connected change of each marker: markers and tracks as one graph, a
    marker joined to the track it gives and the one it takes."""
    edges = [(m, len(before) + t) for m in moved for t in (before[m], after[m]) if t >= 0]
    graph = csr_matrix((np.ones(len(edges)), tuple(np.array(edges).T)), shape=(len(before) + n_tracks,) * 2)
    label: np.ndarray = connected_components(graph, directed=False)[1][: len(before)]
    return label


def _accepted(
    shape: np.ndarray, before: np.ndarray, after: np.ndarray, moved: np.ndarray, change: np.ndarray, sure: np.ndarray,
) -> np.ndarray:
    """``(N,)`` markers whose connected change clears the gain (weighed by ``sure``, module doc) and ratio tests."""
    deviation = np.where(np.isfinite(shape), shape, SHAPE_CAP_MM)

    def cost_of(track: np.ndarray) -> np.ndarray:
        return np.where(track >= 0, deviation[np.arange(len(track)), np.maximum(track, 0)], NONE_MM)

    now, then = cost_of(before), cost_of(after)
    accept = np.zeros(len(before), bool)
    for component in np.unique(change[moved]):
        members = moved[change[moved] == component]
        gain = now[members].sum() - then[members].sum()
        if gain > EXCHANGE_GAIN_MM * sure[members].sum() and then[members].sum() <= EXCHANGE_RATIO * now[members].sum():
            accept[members] = True
    return accept


def _whole_change_fits(state: MarkerState, repaired: MarkerState, change: np.ndarray, accept: np.ndarray) -> np.ndarray:
    """``(N,)`` False for the markers of an accepted change that does not lower, summed over
    its markers, each one's deviation at its own track with every marker where the changes
    put it (``NONE_MM`` for a marker with none): the partners counted (module doc)."""
    now, then = _own_deviations(state), _own_deviations(repaired)
    fits = np.ones(len(accept), bool)
    for component in np.unique(change[accept]):
        members = np.flatnonzero(accept & (change == component))
        fits[members] = then[members].sum() < now[members].sum()
    return fits


def _own_deviations(state: MarkerState) -> np.ndarray:
    """``(N,)`` each seen marker's shape deviation at its own position; ``NONE_MM`` for the others."""
    # D[m, m] alone: the whole (N, N) of ``shape_deviations`` for its diagonal cost N times as much
    own = _deviations_at(state, lengths(state.position[:, None] - state.position[state.neighbours])[:, None])[:, 0]
    return np.where(state.visible & np.isfinite(own), own, NONE_MM)


def reassigned(state: MarkerState, visible: np.ndarray, tracks: np.ndarray, track: np.ndarray) -> MarkerState:
    """Each marker given track ``track[m]`` (index into visible markers then unclaimed points, -1: none)."""
    fields = {name: getattr(state, name).copy() for name in _TRACK_FIELDS}
    for m in np.flatnonzero(track >= 0):
        t = track[m]
        if t < len(visible):  # another marker's track: all it knew about that track
            for name in _TRACK_FIELDS:
                fields[name][m] = getattr(state, name)[visible[t]]
        else:  # a point nobody took: seen now, its motion unknown
            fields["position"][m] = fields["anchor"][m] = fields["seen_at"][m] = tracks[t]
            fields["velocity"][m], fields["velocity_known"][m] = 0.0, False
            fields["unseen"][m], fields["streak"][m] = 0, 1
            fields["anchor_neighbours"][m] = state.position[state.neighbours[m]]
            fields["anchor_valid"][m] = state.visible[state.neighbours[m]]
            fields["anchor_carried"][m] = False
    dropped = np.flatnonzero((track < 0) & state.visible)
    fields["unseen"][dropped], fields["streak"][dropped], fields["seen_at"][dropped] = 1, 0, np.nan
    return replace(state, **fields)
