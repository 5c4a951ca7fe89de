"""Every camera's focal length off alike: the triangulated body is scaled, and a line says so.

Before, a 5 % focal error on every camera of the Pose2Sim rig labeled CMU 85_02 22 mm (median)
off the truth with no line: the cameras agree with each other, and frame 0 sat under 10 px."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_fixtures import camera_capture

from service.capture.capture import LabelingOptions
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.triangulated_scale import triangulated_scale, triangulated_scale_warning


def test_the_scale_is_the_median_ratio_of_near_pairs_to_the_first_frame():
    rng = np.random.default_rng(0)
    first = rng.uniform(-300, 300, (20, 3))
    later = 0.95 * first[None] + rng.normal(0, 0.3, (30, 20, 3)) + [100.0, 0.0, 0.0]  # moved and shrunk
    ratio, count = triangulated_scale(np.concatenate([first[None], later]))
    assert ratio == pytest.approx(0.95, abs=0.002) and count >= 20
    positions = np.concatenate([first[None], first[None] + rng.normal(0, 0.3, (30, 20, 3))])
    assert triangulated_scale_warning(positions) is None
    positions[1:, :5] = np.nan  # unlabeled markers are left out: their pairs do not vote
    assert triangulated_scale(positions)[1] < count


def _focal(camera, factor: float):
    K = camera.K.copy()
    K[0, 0] *= factor
    K[1, 1] *= factor
    return replace(camera, K=K)


@pytest.mark.parametrize("factor", [1.0, 1.05])
def test_a_focal_length_off_on_every_camera_is_said(factor):
    capture = camera_capture(frames=40)
    take = replace(capture, cameras=[_focal(camera, factor) for camera in capture.cameras])
    labeling = CaptureLabeling(take, LabelingOptions())
    labels, windows = labeling.label()
    lines = [line for line in labeling.warnings(labels, windows) if "triangulated markers" in line]
    assert bool(lines) == (factor != 1.0), lines
    if lines:
        assert "closer together" in lines[0] and "focal length" in lines[0]
