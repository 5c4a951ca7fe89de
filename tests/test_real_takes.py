"""Real takes whose subject leaves the volume (issue 14): labeled, not a traceback."""

from __future__ import annotations

import numpy as np
from conftest import DATA

from service.capture.from_recording import capture_from_recording
from service.io.formats import read_labeled
from service.io.recording import Recording
from service.labeling.capture_labeling import CaptureLabeling

WALKING2 = DATA / "mocap_opensim" / "opensim-core_walking2.c3d"
BASKET = DATA / "c3d_kineticstoolkit" / "kinematics_basket_sprint.c3d"


def relabel(recording: Recording) -> tuple[np.ndarray, np.ndarray]:
    """``(F, N)`` occluded and ``(F, N)`` labeled with its own point."""
    result, _ = CaptureLabeling(capture_from_recording(recording)).label()
    return result.occluded, ~result.occluded & np.isclose(result.positions, recording.positions).all(axis=2)


def test_walking2_from_423_whose_subject_walks_out_at_the_end():
    """Frame 423 is the first with all 44 markers; markers leave one by one from frame 1062
    and none is left from 1230 on. Its labeled frame, then the real walk-out."""
    take = read_labeled(WALKING2)
    rows = [423, *range(1200, take.n_frames)]
    recording = Recording(take.names, take.positions[rows], take.rate)
    assert recording.missing()[-19:].all()  # the empty end that crashed
    occluded, _ = relabel(recording)
    assert occluded[-19:].all()


def test_basket_sprint_from_1632_leaving_and_re_entering():
    """The wheelchair leaves the volume at 2181 (empty until 2210) and comes back in parts."""
    take = read_labeled(BASKET)
    markers = [i for i, name in enumerate(take.names) if name != "Sync:Sync"]  # a trigger, not on the subject
    recording = Recording([take.names[i] for i in markers], take.positions[1632:2260, markers], take.rate)
    missing = recording.missing()
    assert missing[2181 - 1632 : 2211 - 1632].all()
    occluded, own = relabel(recording)
    assert occluded[missing.all(axis=1)].all()
    assert own[:500][~missing[:500]].mean() >= 0.9  # the stretch does not reach back


RACING = DATA / "c3d_kineticstoolkit" / "kinematics_racing_full.c3d"


def test_racing_glove_plate_keeps_its_labels_as_it_sweeps():
    """The right glove's three markers are an equilateral 43 mm plate moving 75-90 mm a frame:
    at frames 23, 25 and 27 its labels turned round it, which no distance shows; the turn repair
    (``formulations.markers.turns``) gives them back."""
    take = read_labeled(RACING)
    present = [i for i in range(take.n_markers) if not take.missing()[17, i]]  # Probe1-6 are never seen
    recording = Recording([take.names[i] for i in present], take.positions[17:80, present], take.rate)
    _, own = relabel(recording)
    glove = [recording.names.index(f"GloveR{k}") for k in (1, 2, 3)]
    seen = ~recording.missing()[:, glove]
    assert own[:, glove][seen].mean() >= 0.95
