"""A camera moved since it was calibrated is named: its detections go unused.

The rig through one camera rolled by 10 degrees labeled from the other three (RMSE 5.0 mm
against 1.4) with no line said: its frame-0 offset (8.6 px) is under the frame-0 check's."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest
from capture_fixtures import camera_capture

from service.capture.capture import LabelingOptions
from service.labeling.camera_usage import detections_taken, unused_camera_warning
from service.labeling.capture_labeling import CaptureLabeling


def test_the_share_counts_each_cameras_detections_taken():
    views = np.full((2, 3, 2), -1)
    views[0, 0, 0], views[1, 1, 0], views[1, 2, 1] = 0, 1, 0
    detections = [[np.zeros((10, 2)), np.zeros((12, 2))], [np.zeros((10, 2)), np.zeros((12, 2))]]
    np.testing.assert_allclose(detections_taken(views, detections), [2 / 20, 1 / 24])
    assert np.isnan(detections_taken(views, [[np.zeros((1, 2))] * 2] * 2)).all()  # too few to judge


def test_the_line_names_the_camera_under_half_the_median():
    assert unused_camera_warning(["a", "b", "c"], np.array([0.9, 0.5, 0.95])) is None
    line = unused_camera_warning(["a", "b", "c", "d"], np.array([0.9, 0.08, 0.95, np.nan]))
    assert line is not None and line.startswith("warning: few of some cameras' detections were taken by a marker (b 8%")
    assert unused_camera_warning(["a", "b"], np.array([0.9, 0.08])) is None  # two: which one is off is not told


def _rolled(camera, degrees: float):
    turn = cv2.Rodrigues(np.array([0.0, 0.0, np.radians(degrees)]))[0]  # about the optical axis
    return replace(camera, R=turn @ camera.R, t=turn @ camera.t)


@pytest.mark.parametrize("association", ["joint-3d", "per-camera"])
def test_a_camera_rolled_since_calibration_is_named(association):
    capture = camera_capture(frames=60)
    bumped = replace(capture, cameras=[capture.cameras[0], _rolled(capture.cameras[1], 10.0), *capture.cameras[2:]])
    for take, named in ((capture, None), (bumped, capture.cameras[1].name)):
        labeling = CaptureLabeling(take, LabelingOptions(association=association))
        labels, windows = labeling.label()
        lines = [line for line in labeling.warnings(labels, windows) if "detections were taken" in line]
        assert (lines[0].split("(")[1].split(" ")[0] if lines else None) == named, lines
