"""A label's confidence judged with a second labeling of the same take."""

from __future__ import annotations

import numpy as np

from formulations.confidence.two_readings import agreed_confidence


def test_a_label_both_passes_give_keeps_the_surer_confidence() -> None:
    """A right label one pass doubts only because of its spreads is not doubtful when the
    other reading of the same points is sure of it; both occluded is agreement too."""
    kept, other = np.array([0.30, 0.95, 0.6]), np.array([0.97, 0.40, 0.2])
    labels = np.array([4, 7, -1])
    assert np.allclose(agreed_confidence(kept, labels, other, labels), [0.97, 0.95, 0.6])


def test_labels_that_differ_cannot_both_be_right() -> None:
    """A marker holds one point or none: p(kept right) <= 1 - p(other right)."""
    rng = np.random.default_rng(0)
    kept, other = rng.random(200), rng.random(200)
    kept_label = rng.integers(-1, 3, 200)
    other_label = np.where(rng.random(200) < 0.5, kept_label, (kept_label + 2) % 4 - 1)
    differ = kept_label != other_label
    judged = agreed_confidence(kept, kept_label, other, other_label)
    assert differ.any() and (~differ).any()
    assert np.all(judged[differ] <= 1.0 - other[differ] + 1e-12) and np.all(judged[differ] <= kept[differ])
    assert np.allclose(judged[differ], np.minimum(kept[differ], 1.0 - other[differ]))
    assert np.all(judged[~differ] >= kept[~differ])


def test_a_sure_contradiction_makes_a_sure_label_doubtful() -> None:
    judged = agreed_confidence(np.array([0.99]), np.array([3]), np.array([0.95]), np.array([5]))
    assert np.isclose(judged[0], 0.05)
