"""``shape_breaks`` finds labels that left their rigid neighbours, and only those.

A jointed chain of rigid 4-marker segments (1 mm noise, joints turning). Right labels, a
still first stretch (every pair looks rigid there) and occlusions give no break; labels
rotated among three markers of one segment from a frame on (CMU 135_02's forefoot) or one
marker on another segment's point (03_rolling's arm on the head) are found over exactly
those frames, whatever their confidence. The product then marks them doubtful and says so."""

from __future__ import annotations

import numpy as np
from test_subject_model import chain

from formulations.markers.shape_breaks import shape_breaks
from service.io.recording import LabeledTrajectories
from service.labeling.shape_doubt import SHAPE_BREAK_CONFIDENCE, shape_break_warning, shape_doubted

RATE = 100.0


def _take(seed: int, frames: int = 600) -> tuple[list[str], np.ndarray]:
    names, positions, _ = chain(seed, frames=frames)
    return names, positions


def _broken(breaks: list, frames: int, markers: int) -> np.ndarray:
    flagged = np.zeros((frames, markers), bool)
    for b in breaks:
        flagged[b.start : b.stop, b.marker] = True
    return flagged


def test_right_labels_give_no_break_even_after_a_still_start_and_with_gaps() -> None:
    for seed in range(4):
        names, positions = _take(seed)
        still = np.concatenate([np.repeat(positions[:1], 200, axis=0), positions])  # 2 s without motion
        gappy = still.copy()
        gappy[np.random.default_rng(seed).random(gappy.shape[:2]) < 0.2] = np.nan
        assert shape_breaks(still, RATE) == [] and shape_breaks(gappy, RATE) == []


def test_a_rotation_of_three_labels_is_found_over_its_frames() -> None:
    names, positions = _take(1)
    wrong = positions.copy()
    a, b, c = 4, 5, 6  # three markers of segment S1
    wrong[350:, [a, b, c]] = positions[350:, [b, c, a]]
    flagged = _broken(shape_breaks(wrong, RATE), *wrong.shape[:2])
    # the segment is found in every frame from 350 on; which of its markers are wrong is not
    # decided (a marker moved 200 mm along its segment changes its distances to the others by
    # less than half a spacing, and a right marker among three wrong ones leaves their shape)
    segment = [names.index(f"S1M{m}") for m in range(4)]
    assert flagged[350:, segment].any(axis=1).all()
    assert not flagged[:350].any() and not np.delete(flagged, segment, axis=1).any()


def test_a_marker_on_another_segments_point_is_found_and_its_neighbours_are_not_blamed() -> None:
    names, positions = _take(2)
    wrong = positions.copy()
    wrong[200:420, 1] = positions[200:420, 13]  # S0M1 on S3M1's point
    wrong[200:420, 13] = np.nan  # which is not labeled
    breaks = shape_breaks(wrong, RATE)
    flagged = _broken(breaks, *wrong.shape[:2])
    assert flagged[200:420, 1].mean() >= 0.9
    others = np.delete(flagged, 1, axis=1)
    assert not others.any() and {b.marker for b in breaks} == {1}
    assert breaks[0].off_mm > 100 and names[breaks[0].neighbour].startswith("S0")


def test_labels_in_a_break_are_doubtful_and_the_line_names_them() -> None:
    names, positions = _take(1)
    wrong = positions.copy()
    wrong[350:, [4, 5]] = positions[350:, [5, 4]]
    labels = LabeledTrajectories(names, wrong, np.zeros(wrong.shape[:2], bool), RATE, confidence=np.full(wrong.shape[:2], 0.999))
    doubted, breaks = shape_doubted(labels)
    flagged = _broken(breaks, *wrong.shape[:2])
    assert flagged.any() and (doubted.confidence[flagged] <= SHAPE_BREAK_CONFIDENCE).all()
    assert (doubted.confidence[~flagged] == 0.999).all()
    line = shape_break_warning(breaks, names, first_frame=100)
    assert line is not None and line.startswith("warning: 2 markers left the shape their rigid neighbours keep")
    assert f"{names[breaks[0].marker]} frames {100 + breaks[0].start}-" in line
