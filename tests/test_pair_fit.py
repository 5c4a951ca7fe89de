"""Two-marker groups posed by the joint they turn about (``formulations.subject.pair_fit``)."""

from __future__ import annotations

import numpy as np
import pytest
from test_subject_model import chain

from formulations.subject.fit import fit_subject
from formulations.subject.geometry import ModelGeometry
from formulations.subject.identify import identify
from service.capture.model_input import model_names

FIT = 250


def _two_marker_limb(seed: int):
    """The synthetic chain with its last segment cut to two markers (a thigh or shank of the CMU set)."""
    names, positions, centres = chain(seed, frames=300)
    keep = [i for i, name in enumerate(names) if not name.startswith("S3") or name in ("S3M0", "S3M1")]
    return [names[i] for i in keep], positions[:, keep], centres


@pytest.mark.parametrize("seed", range(3))
def test_a_pair_hangs_from_its_joint_at_the_true_centre(seed: int) -> None:
    names, positions, centres = _two_marker_limb(seed)
    fit = fit_subject(names, positions[:FIT])
    assert ["S3M0", "S3M1"] in [s.markers for s in fit.model.segments]  # not two singles
    assert not fit.model.singles
    joint = next(j for j in fit.model.joints if "S3M0" in j.segments)
    assert set(joint.segments) == {"S2M0", "S3M0"}
    error = np.linalg.norm(fit.centres[joint.name] - centres[2][:FIT], axis=1)
    assert np.nanmedian(error) < 5.0


def test_held_out_frames_name_the_pair_through_its_joint() -> None:
    names, positions, _ = _two_marker_limb(0)
    model = fit_subject(names, positions[:FIT]).model
    geometry = ModelGeometry.of(model)
    order = [names.index(n) for n in model_names(model)]
    pair = [geometry.names.index(n) for n in ("S3M0", "S3M1")]
    rng = np.random.default_rng(1)
    for frame in positions[FIT:, order][::10]:
        points = np.concatenate([frame, frame[rng.integers(0, len(frame), 3)] + rng.normal(0, 150, (3, 3))])
        found = identify(geometry, points)
        assert (found.point[pair] == pair).all()
