"""The job page's figures: every label in exactly one timeline state, detections counted as
used exactly when a labeled marker projects onto them, best views summarised as counted by
hand, and each plot an SVG with its data drawn."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from formulations.cameras.camera import Camera
from service.capture.capture import Capture
from service.io.recording import LabeledTrajectories
from service.labeling.stats import REPORTED_DOUBTFUL_BELOW, WindowStats
from service.web.job_data import Labels, labels_of
from service.web.plots.cameras import USED_PX, best_views, cameras_svg, detections_used
from service.web.plots.certificate import certificate_svg
from service.web.plots.timeline import state_masks, timeline_svg
from service.web.plots.trajectories import chosen_markers, trajectories_svg


def _labels(frames: int, markers: int, seed: int, best_view=None) -> Labels:
    rng = np.random.default_rng(seed)
    occluded = rng.random((frames, markers)) < 0.3
    filled = occluded & (rng.random((frames, markers)) < 0.5)
    doubtful = ~occluded & (rng.random((frames, markers)) < 0.2)
    positions = np.where(occluded[..., None], np.nan, rng.normal(0, 100, (frames, markers, 3)) + 1000)
    return Labels([f"M{m}" for m in range(markers)], 100.0, positions, occluded, filled, doubtful, "test", best_view)


def _drawn_paths(svg: bytes) -> int:
    return len(re.findall(rb'<path[^>]* d="M[^"]+"', svg))


def test_every_label_is_in_exactly_one_timeline_state():
    labels = _labels(50, 7, seed=1)
    masks = np.stack([mask for _, mask in state_masks(labels)])
    assert (masks.sum(axis=0) == 1).all()
    seen, doubtful, filled, occluded = masks
    assert np.array_equal(seen | doubtful, ~labels.occluded)
    assert np.array_equal(filled | occluded, labels.occluded)


def test_a_detection_is_used_exactly_when_a_seen_marker_projects_within_tolerance():
    camera = Camera(K=np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]]), distortion=np.zeros(4), R=np.eye(3),
                    t=np.array([0.0, 0, 2000]), image_size=(640, 480), name="cam1")
    rng = np.random.default_rng(2)
    positions = rng.uniform(-300, 300, (6, 4, 3))
    occluded = np.zeros((6, 4), dtype=bool)
    occluded[2, 1] = True
    projected = camera.project(positions.reshape(-1, 3)).reshape(6, 4, 2)
    # Each marker's detection lies half the tolerance or three times it from its projection.
    angle = rng.uniform(0, 2 * np.pi, (6, 4))
    distance = np.where(rng.random((6, 4)) < 0.5, 0.5 * USED_PX, 3 * USED_PX)
    offsets = distance[..., None] * np.stack([np.cos(angle), np.sin(angle)], axis=2)
    detections = [[projected[f] + offsets[f], np.empty((0, 2))] for f in range(6)]  # cam2 sees nothing
    labels = Labels([f"M{m}" for m in range(4)], 100.0, np.where(occluded[..., None], np.nan, positions), occluded,
                    np.zeros_like(occluded), np.zeros_like(occluded), "test", None)
    other = Camera(K=camera.K, distortion=camera.distortion, R=camera.R, t=camera.t, image_size=camera.image_size,
                   name="cam2")
    capture = Capture(labels.names, positions[0], 100.0, cameras=[camera, other], detections=detections)
    total, used = detections_used(capture, labels)["cam1"]
    # By hand: a detection counts if any seen marker's projection is within USED_PX of it.
    expected = [sum(any(not occluded[f, m] and np.linalg.norm(d - projected[f, m]) <= USED_PX for m in range(4))
                    for d in detections[f][0]) for f in range(6)]
    assert total.tolist() == [4] * 6 and used.tolist() == expected
    assert 0 < sum(expected) < 24  # both kinds occur
    assert _drawn_paths(cameras_svg({"cam1": (total, used)})) > 10


def test_best_views_are_the_most_chosen_camera_and_its_switches():
    views = [["a", None], ["a", "b"], ["b", "b"], ["a", "c"]]
    labels = _labels(4, 2, seed=3, best_view=views)
    assert best_views(labels) == [("M0", "a", 0.75, 2), ("M1", "b", 2 / 3, 1)]
    assert best_views(_labels(4, 2, seed=3)) == []


def test_the_plots_draw_their_data():
    labels = _labels(80, 5, seed=4)
    windows = [WindowStats(template=19 * i, last=19 * (i + 1), integral=i != 1, gap=0.0 if i != 1 else 0.02, cost=1.0,
                           lower_bound=1.0, n_fractional=0, status="optimal", prepare_seconds=0, build_seconds=0,
                           solve_seconds=0.01 * (i + 1), round_seconds=0, total_seconds=0.1, components={})
               for i in range(4)]
    empty_certificate = _drawn_paths(certificate_svg([]))
    # a running job's chart said "3 of 4 windows integral" of 9, as if it were all
    assert b"3 of 4 windows integral (4 of 9 done)" in certificate_svg(windows, total=9)
    assert b"3 of 4 windows integral</dc:title>" in certificate_svg(windows, total=4)
    assert _drawn_paths(certificate_svg(windows)) > empty_certificate
    many = [replace(windows[i % 4], template=19 * i, last=19 * (i + 1)) for i in range(400)]  # stepped outlines
    assert b"300 of 400 windows integral" in certificate_svg(many) and _drawn_paths(certificate_svg(many)) > empty_certificate
    assert _drawn_paths(timeline_svg(labels)) > 5 * 4  # at least a run per marker and state
    assert chosen_markers(labels, ["M3", "nope"]) == ["M3"]
    default = chosen_markers(labels, [])
    assert len(default) == 3 and set(default) <= set(labels.names)
    assert _drawn_paths(trajectories_svg(labels, ["M0", "M1"])) > _drawn_paths(trajectories_svg(labels, ["M0"]))


def test_labels_take_doubt_from_confidence_and_name_the_best_views():
    rng = np.random.default_rng(5)
    occluded = rng.random((30, 4)) < 0.2
    positions = np.where(occluded[..., None], np.nan, rng.normal(size=(30, 4, 3)))
    confidence = rng.random((30, 4))
    confidence[3] = np.nan  # a frame no window labeled: no doubt claimed
    views = rng.integers(-1, 2, (30, 4))
    traj = LabeledTrajectories(["a", "b", "c", "d"], positions, occluded, 100.0, confidence=confidence,
                               best_view=views, view_names=["cam1", "cam2"])
    labels = labels_of(traj)
    assert np.array_equal(labels.doubtful, ~occluded & (np.nan_to_num(confidence, nan=1.0) < REPORTED_DOUBTFUL_BELOW))
    assert labels.best_view == [[{-1: None, 0: "cam1", 1: "cam2"}[int(v)] for v in row] for row in views]
    bare = labels_of(LabeledTrajectories(["a", "b", "c", "d"], positions, occluded, 100.0))
    assert not bare.doubtful.any() and bare.best_view is None and "no per-label confidence" in bare.doubt_source
