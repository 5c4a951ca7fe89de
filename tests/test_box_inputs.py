"""What a detection file, its image and a camera capture say about themselves is checked:
an image size the boxes do not fit, normalised boxes, frames named from the first
detection's frame, full precision out, no best view where a marker has no position, and
no unnamed markers in camera mode (they were ignored without a word)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest
from capture_fixtures import camera_capture, simulated_cmu
from typer.testing import CliRunner

from service.best_view.markers import MarkerViewChoice
from service.boxes.mot_files import read_rows, read_seqinfo
from service.capture.capture import Capture
from service.cli.app import app
from service.errors import InputError
from service.io.formats.csv import read_csv_labeled, write_csv
from service.io.recording import LabeledTrajectories

runner = CliRunner()


def _walkers(path: Path, first: int = 1, scale: float = 1.0) -> Path:
    """Three walkers 300 px apart over 20 frames, from frame ``first``, coordinates times ``scale``."""
    rows = [(first + f, -1, (100 + 300 * p + 3 * f) * scale, 200 * scale, 60 * scale, 150 * scale, 0.9)
            for f in range(20) for p in range(3)]
    path.write_text("".join(",".join(f"{v:.10g}" for v in row) + "\n" for row in rows))
    return path


def _seqinfo(path: Path, extra: str) -> Path:
    path.write_text(f"[Sequence]\nname=x\nseqLength=40\n{extra}")
    return path


def test_boxes_outside_the_seqinfo_image_are_warned_of(tmp_path: Path) -> None:
    det = _walkers(tmp_path / "det.txt")
    fits = runner.invoke(app, ["boxes", str(det), "-o", str(tmp_path / "a.txt"),
                               "--seqinfo", str(_seqinfo(tmp_path / "a.ini", "imWidth=1920\nimHeight=1080\n"))])
    small = runner.invoke(app, ["boxes", str(det), "-o", str(tmp_path / "b.txt"),
                                "--seqinfo", str(_seqinfo(tmp_path / "b.ini", "imWidth=300\nimHeight=300\n"))])
    assert fits.exit_code == small.exit_code == 0
    assert "outside" not in fits.stderr
    assert "40 of 60 detections lie wholly outside the 300 x 300 image of" in small.stderr


def test_a_width_without_a_height_is_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="imWidth without imHeight"):
        read_seqinfo(_seqinfo(tmp_path / "s.ini", "imWidth=1920\n"))


def test_normalised_boxes_are_warned_of_and_written_back_as_given(tmp_path: Path) -> None:
    det = _walkers(tmp_path / "det.txt", scale=1 / 1920)
    run = runner.invoke(app, ["boxes", str(det), "-o", str(tmp_path / "r.txt")])
    assert run.exit_code == 0 and "normalised coordinates?" in run.stderr
    written, given = read_rows(tmp_path / "r.txt"), read_rows(det)
    on_input = np.isin(written[:, 2], given[:, 2])  # boxes taken, not ones held occluded
    assert on_input.sum() >= 50 and np.abs(written[on_input, 2:6][:, None] - given[:, 2:6]).sum(axis=2).min(axis=1).max() < 1e-12


def test_frames_are_read_from_the_first_detections_number(tmp_path: Path) -> None:
    det = _walkers(tmp_path / "det.txt", first=1001)
    images = tmp_path / "img1"
    images.mkdir()
    for f in range(1001, 1021):
        cv2.imwrite(str(images / f"{f:06d}.png"), np.full((1080, 1920), 128, np.uint8))
    run = runner.invoke(app, ["boxes", str(det), "-o", str(tmp_path / "r.txt"), "--images", str(images), "--json"])
    assert run.exit_code == 0, run.output
    (images / "001005.png").unlink()
    missing = runner.invoke(app, ["boxes", str(det), "-o", str(tmp_path / "r.txt"), "--images", str(images)])
    assert missing.exit_code == 2 and "001005.png: missing" in missing.stderr


def test_no_best_view_where_a_marker_has_no_position(tmp_path: Path) -> None:
    cameras, simulated = simulated_cmu(12, 6)
    truth = simulated.truth
    positions = truth.positions[:12].copy()
    positions[4:7, 2] = np.nan  # marker 2 unseen, nothing filled
    labels = LabeledTrajectories(truth.names, positions, np.isnan(positions).any(axis=2), truth.rate)
    views = np.where(np.isnan(positions).any(axis=2)[..., None], -1, 0) + np.zeros(len(cameras), int)
    chosen = MarkerViewChoice(cameras, 1.0, 5).attach(labels, views)
    assert (chosen.best_view[4:7, 2] == -1).all() and (chosen.best_view[:4] >= 0).all()
    write_csv(tmp_path / "v.csv", chosen)
    back = read_csv_labeled(tmp_path / "v.csv")
    assert back.best_view_names() == chosen.best_view_names()
    assert back.best_view_names()[5][2] is None


def test_unnamed_markers_are_refused_in_camera_mode() -> None:
    capture = camera_capture(5, 6)
    with pytest.raises(InputError, match="unnamed tracks are followed in 3D points only"):
        Capture(capture.names, capture.first_frame, capture.rate, cameras=capture.cameras,
                detections=capture.detections, unnamed_markers=2)
    assert replace(capture, unnamed_markers=0).unnamed_markers == 0


def test_a_heuristics_windows_are_not_reported_as_failing_their_certificate(tmp_path: Path) -> None:
    """nn-hungarian proves no bound: its share of integral windows read 0.0, as if every window had failed."""
    import json

    det = _walkers(tmp_path / "det.txt")
    figures = {}
    for name in ("lp-l1", "nn-hungarian"):
        run = runner.invoke(app, ["boxes", str(det), "-o", str(tmp_path / f"{name}.txt"), "--formulation", name, "--json"])
        assert run.exit_code == 0, run.output
        figures[name] = json.loads(run.stdout)["integral_window_fraction"]
    assert figures == {"lp-l1": 1.0, "nn-hungarian": None}
