"""Plates whose markers no distance tells apart: a warning for the take.

A plate of three markers with equal sides (a wheelchair racer's 43 mm triangles) keeps every
one of its distances under any exchange of its labels, so the window's shape term and the
take-wide exchange and rotation repairs (``formulations.markers.take_exchange``,
``take_rotation``), which all judge by distances, see no difference between the readings.
Only a marker rigid with the plate outside it, or how far the plate turned, tells them apart;
a plate lost whole and coming back where nothing rigid carried it may come back exchanged
(the racing take under the accuracy matrix's deletions: its scapula and forearm plates).

A plate here is three labeled markers, each among the other two's ``NEAREST`` nearest in the
labeled frame, whose longest side exceeds the shortest by at most ``EQUAL_SHARE`` of their mean.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
from scipy.spatial import cKDTree

NEAREST = 2  # a plate of three: each marker's two nearest are its plate mates
EQUAL_SHARE = 0.05  # sides within 5 %: racing's plates 1-3 %, a head's four markers 8-20 %
LISTED = 3  # plates named in the warning line


def symmetric_plates(names: list[str], frame: np.ndarray) -> list[tuple[str, str, str]]:
    """The plates of labeled ``frame`` ``(N, 3)`` (NaN rows unlabeled) with equal sides (module doc)."""
    seen = np.flatnonzero(np.isfinite(frame).all(axis=1))
    if len(seen) < NEAREST + 1:
        return []
    _, nearest = cKDTree(frame[seen]).query(frame[seen], k=NEAREST + 1)
    near = {int(m): {int(j) for j in seen[row[1:]]} for m, row in zip(seen, nearest, strict=True)}
    # each of the three names the other two: a, b of m's, and m with the other of a's and b's
    plates = {tuple(sorted((m, a, b))) for m, (a, b) in ((m, sorted(pair)) for m, pair in near.items())
              if near[a] == {m, b} and near[b] == {m, a}}
    found = []
    for plate in sorted(plates):
        sides = [float(np.linalg.norm(frame[i] - frame[j])) for i, j in combinations(plate, 2)]
        if max(sides) - min(sides) <= EQUAL_SHARE * float(np.mean(sides)):
            found.append((names[plate[0]], names[plate[1]], names[plate[2]]))
    return found


def symmetric_plate_warning(plates: list[tuple[str, str, str]]) -> str | None:
    """One line naming the plates (the first ``LISTED``), or None."""
    if not plates:
        return None
    named = ", ".join("/".join(plate) for plate in plates[:LISTED])
    more = f" and {len(plates) - LISTED} more" if len(plates) > LISTED else ""
    return (f"warning: {len(plates)} plates of three markers with equal sides ({named}{more}): an exchange inside one "
            "keeps every distance, so only markers rigid with the plate outside it tell its labels apart; a plate lost "
            "whole may come back exchanged")
