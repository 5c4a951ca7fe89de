"""A fully labeled, fitting segment is read from its labels instead of searched for, and on
clean synthetic takes identification with those readings names the cloud as the full search
does (on real takes it differs where the search misreads such a segment: docs/subject-model.md)."""

from __future__ import annotations

import numpy as np
import pytest
from test_model_start import FIT, _take

from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import identify
from formulations.subject.labeled_reading import labeled_readings
from service.capture.model_input import model_names


def _frames(seed: int = 0):
    names, positions, model = _take(seed)
    order = [names.index(n) for n in model_names(model)]
    return ModelGeometry.of(model), positions[FIT:, order]


def test_a_fully_labeled_segment_that_fits_is_read_from_its_labels() -> None:
    geometry, held = _frames()
    frame = held[50]
    readings = labeled_readings(geometry, np.arange(len(frame)), frame)
    full = [s for s, segment in enumerate(geometry.segments) if len(segment.markers) >= 3]
    assert sorted(readings) == full
    for s in full:
        assert np.array_equal(readings[s].point, geometry.segments[s].markers)
        assert readings[s].rms < geometry.segments[s].tolerance.mean()


def test_a_segment_with_a_marker_unlabeled_or_off_its_place_is_searched() -> None:
    geometry, held = _frames()
    frame = held[50].copy()
    first, second = [s for s, segment in enumerate(geometry.segments) if len(segment.markers) >= 3][:2]
    point_of = np.arange(len(frame))
    point_of[geometry.segments[first].markers[0]] = -1
    moved = geometry.segments[second].markers[0]
    frame[moved] += 5 * geometry.tolerance[moved]
    readings = labeled_readings(geometry, point_of, frame)
    assert first not in readings and second not in readings and len(readings) > 0


@pytest.mark.parametrize("seed", range(3))
def test_identification_with_the_labeled_readings_names_as_the_search_does(seed: int) -> None:
    geometry, held = _frames(seed)
    rng = np.random.default_rng(seed)
    for f in range(0, len(held), 10):
        frame = held[f]
        seen = np.flatnonzero(np.isfinite(frame).all(axis=1) & (rng.random(len(frame)) > 0.1))
        ghosts = frame[seen[:2]] + rng.normal(0, 150, (2, 3))
        order = rng.permutation(len(seen) + 2)
        points = np.concatenate([frame[seen], ghosts])[order]
        point_of = np.full(len(frame), -1)
        point_of[seen] = np.argsort(order)[: len(seen)]  # where each seen marker's point went
        searched = identify(geometry, points)
        read = identify(geometry, points, labeled_readings(geometry, point_of, points))
        assert np.array_equal(searched.point, read.point), f"frame {f}"
