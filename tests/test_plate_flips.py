"""A recording's plate that comes back from a gap with its labels exchanged
(``service.evaluation.plate_flips``; part of ``label_jumps``)."""

from __future__ import annotations

import numpy as np
import pytest

import service.evaluation.label_jumps as jumps_module
from service.evaluation.label_jumps import LabelJumpRule, label_jumps
from service.evaluation.plate_flips import plate_flips
from service.io.recording import Recording

FRAMES = 200
# A four-marker plate (mm): sides 85, 69, 63 and 92, diagonals 119 and 98
# (03_rolling's shank plate: sides 66-93, diagonals 126 and 112).
PLATE = np.array([[0.0, 0.0, 0.0], [85.0, 0.0, 0.0], [97.0, 68.0, 0.0], [36.0, 85.0, 0.0]])


def _plate_take(exchanged: bool, seed: int = 0) -> Recording:
    """The plate turning and moving for ``FRAMES`` frames with 0.5 mm noise, unseen over 150-169;
    with ``exchanged`` its labels 0/1 and 2/3 are exchanged from 170 to the end (a half turn,
    over a sixth of the frames that see it, as 03_rolling's over the last 5-8 %)."""
    rng = np.random.default_rng(seed)
    angle = np.linspace(0, 2, FRAMES)
    c, s = np.cos(angle), np.sin(angle)
    turn = np.stack([np.stack([c, -s, 0 * c], 1), np.stack([s, c, 0 * c], 1), np.tile([0, 0, 1.0], (FRAMES, 1))], 1)
    positions = np.einsum("fij,nj->fni", turn, PLATE) + np.linspace(0, 600, FRAMES)[:, None, None]
    positions += rng.normal(0.0, 0.5, positions.shape)
    if exchanged:
        positions[170:] = positions[170:, [1, 0, 3, 2]]
    positions[150:170] = np.nan
    return Recording(["sk1", "sk2", "sk3", "sk4"], positions, 100.0)


def test_a_plate_back_from_a_gap_with_its_labels_exchanged_is_left_out_after_it() -> None:
    jumped = plate_flips(_plate_take(exchanged=True))
    assert jumped[170:].all()
    assert not jumped[:150].any()


def test_one_marker_at_a_time_does_not_see_the_exchange_the_plate_does(monkeypatch: pytest.MonkeyPatch) -> None:
    """The setup: only each marker's diagonal partner moved, so the per-marker median change
    stays under ``jump_mm``: ``label_jumps`` without plates misses it, with them finds it."""
    take = _plate_take(exchanged=True)
    diagonal_change = abs(np.linalg.norm(PLATE[0] - PLATE[2]) - np.linalg.norm(PLATE[1] - PLATE[3]))
    assert 10.0 < diagonal_change < LabelJumpRule().jump_mm
    assert label_jumps(take)[170:].all()
    monkeypatch.setattr(jumps_module, "plate_flips", lambda recording: np.zeros(recording.positions.shape[:2], bool))
    assert not label_jumps(take).any()


def test_a_plate_kept_as_it_was_and_a_symmetric_plate_are_left_alone() -> None:
    assert not plate_flips(_plate_take(exchanged=False)).any()
    side = np.array([[0.0, 0.0, 0.0], [80.0, 0.0, 0.0], [80.0, 80.0, 0.0], [0.0, 80.0, 0.0]])
    assert not plate_flips(_square_take(side)).any()  # its exchanged labels fit as well: nothing to tell


def _square_take(side: np.ndarray) -> Recording:
    """A square plate whose labels are exchanged after a gap, as ``_plate_take``: the exchange keeps every distance."""
    positions = np.linspace(0, 600, FRAMES)[:, None, None] + side[None]
    positions = positions + np.random.default_rng(1).normal(0.0, 0.5, positions.shape)
    positions[170:] = positions[170:, [1, 0, 3, 2]]
    positions[150:170] = np.nan
    return Recording(["a", "b", "c", "d"], positions, 100.0)
