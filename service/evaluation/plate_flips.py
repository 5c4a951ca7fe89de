"""Where a recording's own labels come back from a gap with a rigid plate's markers exchanged:
its ground truth is not truth there either (``label_jumps``).

numediart's 03_rolling loses its right thigh plate (LR_TH1-4) and its right shank plate
(LR-SK1, LR_SK2-4) for a while near its end, and both come back in the file half turned: the
plate's two diagonals exchange their lengths (TH1-TH3 and TH2-TH4 115 and 173 mm before, 175
and 111 mm after; SK1-SK3 and SK2-SK4 126 and 112 mm before, 112 and 126 mm after) while its
sides keep theirs, which no rigid plate does and the exchange of both label pairs gives
exactly. ``label_jumps`` reads each marker against its partners one at a time (the median
change), and a half turn moves only the diagonal partner, so it does not see this.

Here a plate is read whole. Each marker's plate is the marker and its three nearest partners
rigid with it over the take (``PairSpreads``: the median absolute deviation of their
distance, robust to a plate exchanged over under half the frames, at most ``rigid_mm`` as an
s.d.; the reference distances are the take's medians), where those are rigid with each other
too. Each stretch of frames that
sees the whole plate (at least ``min_frames``) is compared with the reference by its median
distances: where the plate's own labels misfit by more than ``flip_mm`` on some pair, and
another assignment of the four labels fits every pair within ``rigid_mm``, that stretch's
labels are exchanged, and the marker-frames of the markers the assignment moves are left
out of a score. A plate whose exchange keeps every distance (a square) is never flagged:
nothing tells it.

On the recordings of ``service.evaluation.matrix.RECORDINGS`` this flags 03_rolling's right
shank plate from frame 2181 (496 marker-frames, 0.3 s) and nothing else. Its right thigh plate
is not flagged: over the take its pairs spread 5.6-6.2 mm (it sits on soft tissue), over
``rigid_mm``, so it is no plate by this rule.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import permutations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.pair_spread import PairSpreads
from formulations.markers.runs import runs
from service.io.recording import Recording

Mask = NDArray[np.bool_]
Array = NDArray[np.float64]
PLATE = 4  # markers read together: a plate, or a segment's four nearest rigid markers


@dataclass(frozen=True)
class PlateFlipRule:
    """When a plate's labels came back exchanged (module doc)."""

    rigid_mm: float = 5.0  # as ``LabelJumpRule.rigid_mm``
    flip_mm: float = 10.0  # twice that: far beyond a rigid pair's spread, short of a diagonal's change
    min_frames: int = 10


def plate_flips(recording: Recording, rule: PlateFlipRule = PlateFlipRule()) -> Mask:
    """``(frames, markers)`` the marker-frames of plates whose labels came back exchanged."""
    seen = ~recording.missing()
    flipped = np.zeros_like(seen)
    spreads = PairSpreads(recording.positions)
    for plate in _plates(spreads, seen.shape[1], rule.rigid_mm):
        whole: Mask = np.asarray(seen[:, plate].all(axis=1), dtype=bool)
        reference = spreads.median(plate, plate)
        for start, length in runs(whole):
            if length >= rule.min_frames:
                span = slice(start, start + length)
                moved = _moved_labels(_distances(recording.positions[span][:, plate]), reference, rule)
                flipped[span, np.asarray(plate)[moved]] = True
    return flipped


def _plates(spreads: PairSpreads, n: int, rigid_mm: float) -> list[list[int]]:
    """Each marker with its three nearest rigid partners, where those are rigid with each other
    too, once each."""
    markers, plates = list(range(n)), set()
    for m in markers:
        var, length = spreads.var([m], markers)[0], spreads.median([m], markers)[0]
        partners = np.flatnonzero(var <= rigid_mm**2)  # inf for m itself
        plate = [m, *partners[np.argsort(length[partners], kind="stable")[: PLATE - 1]].tolist()]
        if len(plate) == PLATE and (spreads.var(plate, plate)[np.triu_indices(PLATE, 1)] <= rigid_mm**2).all():
            plates.add(tuple(sorted(plate)))  # a plate, not a joint's two sides
    return [list(plate) for plate in sorted(plates)]


def _distances(positions: Array) -> Array:
    """``(P, P)`` median distances between a plate's markers over a stretch ``(L, P, 3)``."""
    return np.median(np.linalg.norm(positions[:, :, None] - positions[:, None], axis=3), axis=0)


def _moved_labels(seen: Array, reference: Array, rule: PlateFlipRule) -> Mask:
    """``(P,)`` the labels an exchange moves where the stretch's distances ``seen`` fit the
    reference only so (module doc); none where its own labels fit or nothing else does."""
    upper = np.triu_indices(len(seen), 1)
    if np.abs(seen - reference)[upper].max() <= rule.flip_mm:
        return np.zeros(len(seen), bool)
    for order in permutations(range(len(seen))):
        index = np.asarray(order)
        if np.abs(seen - reference[np.ix_(index, index)])[upper].max() <= rule.rigid_mm:
            moved: Mask = index != np.arange(len(seen))
            return moved
    return np.zeros(len(seen), bool)
