"""A take in the wrong unit: ``track`` refuses metres read as mm and mm read as metres before
labeling; ``model``, ``eval`` and a job's warnings name the unit read and what looks wrong."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_input_bounds_io import take, write_c3d

from service.labeling.take_warnings import scale_warning


@pytest.mark.parametrize("scale", [1.0, 0.1, 10.0])
def test_human_sized_takes_raise_no_scale_warning(scale):
    positions = take(scale=scale)
    assert scale_warning(positions[0], positions, 100.0, "mm") is None


@pytest.mark.parametrize("scale,spacing", [(1000.0, "7e+04 mm"), (0.001, "0.07 mm")])
def test_wrong_unit_spacing_is_warned(scale, spacing):
    positions = take(scale=scale)
    line = scale_warning(positions[0], positions, 100.0, "mm")
    assert line is not None and line.startswith("warning: read in mm,")
    assert f"markers {spacing} from their nearest neighbour" in line


def test_implausible_speed_is_warned_with_the_rate():
    positions = take()
    line = scale_warning(positions[0], positions, 1e5, "m")  # 10 mm a frame at 100 kHz: 1 km/s
    assert line is not None and "read in m," in line and "1e+03 m/s at 100000 Hz" in line
    assert line.endswith("check the file's length unit and frame rate")


BODY = ["LASI", "RASI", "LKNE", "RKNE", "LANK", "RANK", "LHEE", "RHEE", "C7", "CLAV"]


def _body(scale: float) -> np.ndarray:
    """``(2, 10, 3)`` mm: a standing body's landmarks (pelvis, knees, ankles, heels, neck), times ``scale``."""
    heights = np.array([950.0, 950, 500, 500, 90, 90, 40, 40, 1450, 1400])
    sides = np.array([-120.0, 120, -100, 100, -100, 100, -100, 100, 0, 0])
    frame = np.column_stack([sides, np.zeros(10), heights])
    return scale * np.stack([frame, frame + [5.0, 0, 0]])


def test_a_body_in_cm_read_as_mm_is_warned_of_by_its_landmarks():
    """Ten times small, a body keeps its markers far enough apart for the spacing rule (CMU
    85_02 in cm read as mm: 11 mm); its landmark names say it cannot fit in 150 mm."""
    small = _body(0.1)
    line = scale_warning(small[0], small, 100.0, "mm", names=BODY)
    assert line is not None and "10 markers, LASI, RASI, LKNE, RKNE among them, within 141 mm" in line
    assert scale_warning(_body(1.0)[0], _body(1.0), 100.0, "mm", names=BODY) is None
    hand = [f"F{k}" for k in range(10)]  # a hand or face set in mm is as small: no landmark names
    assert scale_warning(small[0], small, 100.0, "mm", names=hand) is None
    face = [f"{side}Cheek{k}" for side in "LR" for k in range(5)]  # "Cheek" holds HEE, not a heel
    assert scale_warning(small[0], small, 100.0, "mm", names=face) is None


def test_one_marker_and_unlabeled_frames_have_no_scale_to_judge():
    positions = np.full((5, 1, 3), np.nan)
    positions[0] = 1.0
    assert scale_warning(positions[0], positions, 100.0, "mm") is None


@pytest.mark.parametrize(("scale", "said"), [
    # every point in every gate: 20 frames of a walk ran for over ten minutes, the unit line printed only at the start
    (1e-3, "markers 0.07 mm from their nearest neighbour in the first frame: optical markers are millimetres wide"),
    # millimetres read as metres: labeled after a warning and written 100 % occluded, exit code 0
    (1e3, "markers 70 m from their nearest neighbour in the first frame: markers on a subject are centimetres apart"),
], ids=["metres-as-mm", "mm-as-metres"])
def test_track_refuses_a_take_in_the_wrong_unit_before_labeling(tmp_path, scale, said):
    path = write_c3d(tmp_path / "take.c3d", take() * scale, unit="mm")
    run = subprocess.run([sys.executable, "-m", "service.cli", "track", str(path), "-o", str(tmp_path / "o.trc")],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2 and not (tmp_path / "o.trc").exists(), run.stderr[-2000:]
    assert run.stderr.startswith(f"error: {said}, so the take's length unit is wrong"), run.stderr
    assert len(run.stderr.splitlines()) == 1


def test_model_and_eval_warn_of_a_take_in_metres_labelled_mm(tmp_path):
    """``model`` blamed a lack of motion ("too static") and ``eval`` scored 0 % silently."""
    path = write_c3d(tmp_path / "metres.c3d", take() / 1000.0, unit="mm")
    for args in (["model", str(path), "--out", str(tmp_path / "m.json")],
                 ["eval", str(path), "--scenario", str(Path(__file__).parents[1] / "configs" / "scenarios" / "clean.toml")]):
        run = subprocess.run([sys.executable, "-m", "service.cli", *args], capture_output=True, text=True, timeout=300)
        assert "the take does not look human-sized: markers 0.07 mm" in run.stderr, (args[0], run.stderr[-2000:])


def test_a_jobs_warnings_say_a_body_in_cm_read_as_mm_too():
    """The service's job warnings (``result_warnings``) judged the spacing without the names."""
    from service.capture.capture import Capture
    from service.labeling.capture_labeling import CaptureLabeling
    from service.labeling.result_warnings import result_warnings

    small = np.concatenate([_body(0.1) + [0.5 * k, 0.0, 0.0] for k in range(6)])  # 12 frames, walking slowly
    capture = Capture(BODY, small[0], 100.0, points=list(small))
    labels = CaptureLabeling(capture).label()[0]
    assert any("(a body in cm read as mm?)" in line for line in result_warnings(capture, labels, []))
    face = Capture([f"F{k}" for k in range(10)], small[0], 100.0, points=list(small))
    assert not any("cm read as mm" in line for line in result_warnings(face, CaptureLabeling(face).label()[0], []))
