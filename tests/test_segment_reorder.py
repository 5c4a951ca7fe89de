"""A contradicting segment read again on its own points (``subject.reorder``), and recovery
using that reading where the frame's identification cannot be used."""

from __future__ import annotations

from dataclasses import replace
from itertools import permutations

import numpy as np
from test_model_fill import _held_out

from formulations.markers.state import MarkerState
from formulations.subject.contradiction import contradicting
from formulations.subject.identify import Identification
from formulations.subject.recover import recover
from formulations.subject.reorder import reordered


def _nothing_named(n: int) -> Identification:
    """An identification that names no marker (the frame's reading was of no use)."""
    return Identification(np.full(n, -1, dtype=np.int64), np.full(n, np.nan), np.full((n, 3), np.nan))


def test_an_exchange_is_undone_and_agrees_with_brute_force() -> None:
    _, geometry, held = _held_out()
    for s, segment in enumerate(geometry.segments):
        if len(segment.markers) < 3:
            continue
        frame = held[60].copy()
        a, b = segment.markers[:2]
        frame[[a, b]] = frame[[b, a]]
        order = reordered(geometry, s, frame)
        assert order is not None
        fixed = frame.copy()
        fixed[order] = frame[segment.markers]
        assert np.allclose(fixed[segment.markers], held[60, segment.markers])
        # brute force over every order of the segment's points: the true one fits best
        points = frame[segment.markers]
        rms = {p: _kabsch_rms(segment.coordinates[list(p)], points) for p in permutations(range(len(segment.markers)))}
        best = min(rms, key=rms.__getitem__)
        assert np.array_equal(segment.markers[list(best)], order)


def _kabsch_rms(source: np.ndarray, target: np.ndarray) -> float:
    a, b = source - source.mean(0), target - target.mean(0)
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(u @ vt))
    rotation = (u @ np.diag([1, 1, d]) @ vt).T
    return float(np.sqrt(((a @ rotation.T - b) ** 2).sum(1).mean()))


def test_labels_that_fit_and_a_ghost_are_left_alone() -> None:
    _, geometry, held = _held_out()
    s = next(k for k, seg in enumerate(geometry.segments) if len(seg.markers) >= 3)
    assert reordered(geometry, s, held[60]) is None
    ghost = held[60].copy()
    ghost[geometry.segments[s].markers[0]] += np.array([0.0, 0.0, 400.0])
    assert reordered(geometry, s, ghost) is None  # no order of these points fits the segment


def test_a_point_held_by_the_wrong_mate_goes_to_the_unseen_one() -> None:
    _, geometry, held = _held_out()
    s = next(k for k, seg in enumerate(geometry.segments) if len(seg.markers) >= 4)
    a, b = geometry.segments[s].markers[:2]
    frame = held[60].copy()
    frame[b], frame[a] = frame[a], np.nan  # b holds a's point, a unseen
    order = reordered(geometry, s, frame)
    assert order is not None and a in order and b not in order


def test_recovery_reorders_when_the_identification_names_nothing() -> None:
    _, geometry, held = _held_out()
    frame = held[60]
    segment = geometry.segments[2]
    a, b = segment.markers[:2]
    swapped = frame.copy()
    swapped[[a, b]] = swapped[[b, a]]
    broken = replace(MarkerState.from_first_frame(frame), position=swapped)
    assert contradicting(geometry, swapped)[2]
    repaired, segments = recover(geometry, broken, frame, lambda: _nothing_named(len(frame)))
    assert segments == [2]
    assert np.allclose(repaired.position[[a, b]], frame[[a, b]])
    assert not repaired.velocity_known[[a, b]].any()  # re-read: its motion starts again
