"""A marker the labeled frame names but the subject model lacks becomes a single of the model,
measured in that frame (``formulations/subject/labeled_singles.py``)."""

from __future__ import annotations

import numpy as np
from test_subject_model import chain

from formulations.subject.fit import fit_subject
from formulations.subject.geometry import ModelGeometry
from formulations.subject.labeled_singles import with_labeled_singles


def test_a_lacking_marker_is_measured_from_the_two_nearest_posed_segments() -> None:
    names, positions, _ = chain(2, frames=200)
    model = fit_subject(names, positions[:150]).model
    frame = positions[160]
    extra = frame[names.index("S2M0")] + np.array([40.0, -30.0, 20.0])
    labeled = np.vstack([frame, extra, np.full(3, np.nan)])
    grown = with_labeled_singles(model, [*names, "EXTRA", "UNSEEN"], labeled)
    assert [s.marker for s in grown.singles] == ["EXTRA"]  # UNSEEN is not labeled: nothing to measure
    [single] = grown.singles
    geometry = ModelGeometry.of(model)
    origins = {s.name: frame[[names.index(geometry.names[m]) for m in s.markers]].mean(axis=0) for s in geometry.segments}
    brute = sorted((float(np.linalg.norm(origin - extra)), name) for name, origin in origins.items())[:2]
    assert single.segments == [name for _, name in brute]
    np.testing.assert_allclose(single.distances, [d for d, _ in brute], atol=0.05)  # the fitted origin is the centroid
    assert ModelGeometry.of(grown).names[-1] == "EXTRA"


def test_nothing_posed_leaves_the_lacking_markers_out() -> None:
    names, positions, _ = chain(2, frames=200)
    model = fit_subject(names, positions[:150]).model
    unlabeled = np.full((len(names) + 1, 3), np.nan)
    unlabeled[-1] = positions[160, 0]
    assert with_labeled_singles(model, [*names, "EXTRA"], unlabeled) == model  # EXTRA left out
