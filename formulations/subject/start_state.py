"""The labeler's first marker state from a subject model instead of a labeled frame.

Named markers start where identification put them. A marker left unnamed starts where its
segment's pose puts it when the segment was placed, else at the centroid of the named
markers, and counts as unseen for ``lost_after`` frames: it follows its neighbours while
they are seen, and is looked for by re-acquisition otherwise, until the model names it
(``acquire``). The neighbours of each marker are the other markers of its segment first
(their distances are the model's, their variance its spread), then the nearest others.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from formulations.markers.state import MarkerState
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import Identification

Array = NDArray[np.float64]
UNRELATED_VAR = 100.0  # mm^2: the prior variance MarkerState gives a distance it has not measured


def model_start_state(
    geometry: ModelGeometry, found: Identification, points: Array, lost_after: int, n_neighbours: int = 16,
    misfit: frozenset[str] = frozenset(),
) -> MarkerState:
    """The state at the identified frame; markers follow ``geometry.names``. The markers of a
    segment in ``misfit`` (names the labeled frame contradicts, ``contradiction.labeled_misfits``)
    take their nearest markers as neighbours, not the model's segment-mates.

    Raises:
        ValueError: No marker was named (nothing to start from).
    """
    named = found.named
    if not named.any():
        raise ValueError("no marker of the model was identified in the start frame")
    position = np.where(np.isfinite(found.placed), found.placed, points[found.point[named]].mean(axis=0))
    position[named] = points[found.point[named]]
    state = MarkerState.from_first_frame(position, n_neighbours)
    neighbours, mean, var = _segment_neighbours(geometry, position, state.neighbours.shape[1], misfit)
    unseen = np.where(named, 0, lost_after)
    return replace(
        state, neighbours=neighbours, unseen=unseen, streak=named.astype(int),
        anchor_neighbours=position[neighbours], anchor_valid=named[neighbours], distance_mean=mean, distance_var=var,
        seen_at=np.where(named[:, None], position, np.nan),
    )


def acquire(state: MarkerState, markers: NDArray[np.int64], positions: Array) -> MarkerState:
    """``state`` with ``markers`` seen now at ``positions`` (velocity unknown: just acquired)."""
    seen = np.zeros(len(state.position), bool)
    seen[markers] = True
    position = state.position.copy()
    position[markers] = positions
    visible = state.visible | seen
    return replace(
        state, position=position, velocity=np.where(seen[:, None], 0.0, state.velocity),
        velocity_known=state.velocity_known & ~seen, unseen=np.where(seen, 0, state.unseen),
        streak=np.where(seen, 1, state.streak), anchor=np.where(seen[:, None], position, state.anchor),
        anchor_neighbours=np.where(seen[:, None, None], position[state.neighbours], state.anchor_neighbours),
        anchor_valid=np.where(seen[:, None], visible[state.neighbours], state.anchor_valid),
        seen_at=np.where(seen[:, None], position, state.seen_at),
    )


def _segment_neighbours(
    geometry: ModelGeometry, position: Array, k: int, misfit: frozenset[str],
) -> tuple[NDArray[np.int64], Array, Array]:
    """``(N, k)`` neighbours (same segment first, then nearest), their distances and variances;
    a segment in ``misfit`` is no segment here: a model that lumped it (fitted where the subject
    barely moved) would tie its markers to mates they move apart from (03_rolling from frame 562,
    a model of frames 0-561 whose head and left-arm groups the labels contradict: 82.88 % with
    their mates, 89.23 % without)."""
    n = len(position)
    gap = np.linalg.norm(position[:, None] - position[None], axis=2)
    model_distance = np.full((n, n), np.nan)
    model_var = np.full((n, n), UNRELATED_VAR)
    for segment in (g for g in geometry.segments if g.name not in misfit):
        u, m = segment.coordinates, segment.markers
        model_distance[np.ix_(m, m)] = np.linalg.norm(u[:, None] - u[None], axis=2)
        model_var[np.ix_(m, m)] = segment.spread[:, None] ** 2 + segment.spread[None] ** 2
    rank = np.where(np.isfinite(model_distance), gap - 1e6, gap)  # same segment sorts first
    np.fill_diagonal(rank, np.inf)
    neighbours = np.argsort(rank, axis=1)[:, :k]
    rows = np.arange(n)[:, None]
    mean = np.where(np.isfinite(model_distance[rows, neighbours]), model_distance[rows, neighbours], gap[rows, neighbours])
    return neighbours, mean, model_var[rows, neighbours]
