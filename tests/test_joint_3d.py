"""joint-3d association end to end on real motion through a real calibration.

CMU 85_02 placed in the Pose2Sim 4-camera rig: 0.5 px noise, 3 px blob merging, 10 %
per-camera occlusion in 15-frame bursts, 2 clutter points per camera. The figures are
the level reached so far (issue 3 asks for 99.5 %; these 300 frames give 99.98 %, the
whole recording 99.83 %); they may not get worse.
"""

import numpy as np
import pytest
from capture_fixtures import capture_of, seen_once_in_frame0, simulated_cmu

from service.capture.capture import LabelingOptions
from service.evaluation.camera_scores import camera_scores
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.joint_3d import cross_camera_cloud

FRAMES = 300


def test_joint_3d_labels_cmu_85_02_through_the_pose2sim_rig():
    cameras, capture = simulated_cmu(FRAMES)
    names = capture.first_frame.names
    cloud, _ = cross_camera_cloud(cameras, capture.detections, capture.truth.rate)
    # Points share detections: the cloud's resources are what the conflict rows use.
    assert all(
        r.shape == (len(p), sum(len(d) for d in det))
        for r, p, det in zip(cloud.resources, cloud.points, capture.detections)
    )
    labeling = CaptureLabeling(capture_of(cameras, capture))
    outcomes = list(labeling.windows())
    result, windows = labeling.result(outcomes), [o.stats for o in outcomes]
    scores = camera_scores(capture.marker_detection, capture.truth.positions, result, labeling.views(outcomes))
    assert scores.marker_frames > 0.9 * (FRAMES - 1) * len(names)
    assert scores.label_accuracy >= 0.999
    assert scores.rmse_mm <= 3.0
    # Occluded markers carry their predicted position, flagged by `occluded`.
    assert np.isfinite(result.filled[result.occluded]).all() and np.isnan(result.filled[~result.occluded]).all()
    assert scores.rmse_mm < scores.filled_rmse_mm < 100.0
    assert np.mean([w.integral for w in windows]) == 1.0


@pytest.mark.parametrize("association", ["joint-3d", "per-camera"])
def test_frame_0_of_the_result_is_the_labeled_frame(association):
    """joint-3d returned frame 0's cross-camera points (triangulated again, up to 2.3 mm off
    the given positions) and a labeled marker only one camera saw there as occluded."""
    cameras, simulated = simulated_cmu(20, markers=12)
    hidden = 5
    capture, expected = seen_once_in_frame0(cameras, simulated, hidden)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10, association=association))
    outcomes = list(labeling.windows())
    result, views = labeling.result(outcomes), labeling.views(outcomes)
    np.testing.assert_array_equal(result.positions[0], capture.first_frame)
    assert not result.occluded[0].any()
    others = np.arange(len(capture.names)) != hidden  # joint-3d's views of the hidden marker: none (no point)
    np.testing.assert_array_equal(views[0, others], expected[others])
