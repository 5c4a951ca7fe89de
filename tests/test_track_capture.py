"""``markerflow track capture.json`` in both input modes, and its one-line errors."""

from __future__ import annotations

import json

import ezc3d
import numpy as np
from capture_fixtures import camera_capture, points_capture
from test_cli import run_cli

from service.capture.capture import LabelingOptions
from service.capture.document import CaptureDocument
from service.labeling.capture_labeling import CaptureLabeling


def test_track_labels_a_camera_capture_json_like_the_library(tmp_path):
    capture = camera_capture(frames=30, markers=12)
    source = tmp_path / "capture.json"
    source.write_text(CaptureDocument.of(capture, LabelingOptions(window=10)).model_dump_json())
    done = run_cli("track", source, "--out", tmp_path / "labeled.c3d")
    assert done.returncode == 0, done.stderr
    assert "12 markers x 30 frames (cameras)" in done.stdout
    written = ezc3d.c3d(str(tmp_path / "labeled.c3d"))
    expected, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    assert written["parameters"]["POINT"]["LABELS"]["value"] == capture.names
    positions = written["data"]["points"][:3].transpose(2, 1, 0)
    assert np.allclose(positions[~expected.occluded], expected.positions[~expected.occluded], atol=1e-3)


def test_track_options_on_the_command_line_override_the_document(tmp_path):
    source = tmp_path / "capture.json"
    source.write_text(CaptureDocument.of(points_capture(frames=10), LabelingOptions(window=5)).model_dump_json())
    assert run_cli("track", source, "--out", tmp_path / "a.csv").returncode == 0
    bad = run_cli("track", source, "--out", tmp_path / "b.csv", "--window", "1")
    assert bad.returncode == 2
    assert bad.stderr.strip() == "error: --window must be at least 2 frames (a template and one new frame), got 1"


def test_track_reports_a_bad_capture_in_one_line(tmp_path):
    document = json.loads(CaptureDocument.of(camera_capture(frames=4, markers=5)).model_dump_json())
    camera = document["cameras"][0]["name"]
    document["detections"][camera][1].append([-40.0, 12.0])
    source = tmp_path / "capture.json"
    source.write_text(json.dumps(document))
    done = run_cli("track", source, "--out", tmp_path / "out.c3d")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert f"detections.{camera}.1." in done.stderr and "is outside the" in done.stderr
    assert not (tmp_path / "out.c3d").exists()


def test_a_first_frame_off_every_camera_is_refused_naming_the_file(tmp_path):
    """Every other error of a capture JSON starts with its file name; this one did not."""
    document = json.loads(CaptureDocument.of(camera_capture(frames=4, markers=12)).model_dump_json())
    document["first_frame"] = [[x + 400.0, y, z] for x, y, z in document["first_frame"]]  # 400 mm off
    source = tmp_path / "capture.json"
    source.write_text(json.dumps(document))
    done = run_cli("track", source, "--out", tmp_path / "out.c3d")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert done.stderr.startswith(f"error: {source}: the labeled first frame does not land on frame 0's detections")
