"""joint-3d association end to end on real motion through a real calibration.

CMU 85_02 placed in the Pose2Sim 4-camera rig: 0.5 px noise, 3 px blob merging, 10 %
per-camera occlusion in 15-frame bursts, 2 clutter points per camera. The figures are
the level reached so far (issue 3 asks for 99.5 %; these 300 frames give 99.98 %, the
whole recording 99.83 %); they may not get worse.
"""

import numpy as np
from conftest import DATA

from service.calibration import load_pose2sim_toml
from service.camera_scores import camera_scores, joint_3d_views
from service.cloud_labeler import CloudLabeler
from service.formats import read_labeled
from service.joint_3d import cross_camera_cloud
from service.recording import Recording
from service.simulate_cameras import CameraRig, place_in_volume, simulate_cameras

FRAMES = 300


def test_joint_3d_labels_cmu_85_02_through_the_pose2sim_rig():
    cameras = load_pose2sim_toml(DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml", units="mm")
    rig = CameraRig.from_cameras(cameras)
    truth = read_labeled(DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d")
    placed = Recording(truth.names, place_in_volume(truth.positions[:FRAMES], rig), truth.rate)
    capture = simulate_cameras(placed, rig, pixel_noise=0.5, merge_radius_px=3.0, occlusion_rate=0.1,
                               occlusion_burst_frames=15, clutter_per_camera=2, seed=0)
    cloud, matched = cross_camera_cloud(cameras, capture.detections, truth.rate)
    # Points share detections: the cloud's resources are what the conflict rows use.
    assert all(r.shape == (len(p), sum(len(d) for d in det)) for r, p, det in zip(cloud.resources, cloud.points, capture.detections))
    result, windows = CloudLabeler().label(cloud, capture.first_frame.names, capture.first_frame.positions[0])
    scores = camera_scores(capture.marker_detection, capture.truth.positions, result, joint_3d_views(result, matched))
    assert scores.marker_frames > 0.9 * (FRAMES - 1) * len(truth.names)
    assert scores.label_accuracy >= 0.999
    assert scores.rmse_mm <= 3.0
    # Occluded markers carry their predicted position, flagged by `occluded`.
    assert np.isfinite(result.filled[result.occluded]).all() and np.isnan(result.filled[~result.occluded]).all()
    assert scores.rmse_mm < scores.filled_rmse_mm < 100.0
    assert np.mean([w.integral for w in windows]) == 1.0
