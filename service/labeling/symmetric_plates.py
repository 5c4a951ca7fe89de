"""Plates whose markers no distance tells apart: a warning for the take.

A plate of three markers with equal sides (a wheelchair racer's 43 mm triangles) keeps every
one of its distances under any exchange of its labels, so the window's shape term and the
take-wide exchange and rotation repairs (``formulations.markers.take_exchange``,
``take_rotation``), which all judge by distances, see no difference between the readings.
Only a marker rigid with the plate outside it, or how far the plate turned, tells them apart;
a plate lost whole and coming back where nothing rigid carried it may come back exchanged
(the racing take under the accuracy matrix's deletions: its scapula and forearm plates).

A plate here is what ``plate_turns.equal_plates`` finds: three markers each among the other
two's nearest in the first frame, their median sides over the take within ``EQUAL_SHARE``
of one another and rigid. Where the plate was seen whole in frames near enough for its turn
to tell, ``plate_turns`` gives such exchanges back; the warning stays for the rest.
"""

from __future__ import annotations

import numpy as np

from formulations.markers.plate_turns import equal_plates
from service.words import counted

LISTED = 3  # plates named in the warning line


def symmetric_plates(names: list[str], positions: np.ndarray, first: np.ndarray) -> list[tuple[str, str, str]]:
    """The plates with equal sides (module doc) of labeled ``positions`` ``(F, N, 3)`` (NaN
    unlabeled) with labeled first frame ``first`` ``(N, 3)``, by name."""
    return [(names[a], names[b], names[c]) for a, b, c in equal_plates(positions, first)]


def symmetric_plate_warning(plates: list[tuple[str, str, str]]) -> str | None:
    """One line naming the plates (the first ``LISTED``), or None."""
    if not plates:
        return None
    named = ", ".join("/".join(plate) for plate in plates[:LISTED])
    more = f" and {len(plates) - LISTED} more" if len(plates) > LISTED else ""
    return (f"warning: {counted(len(plates), 'plate')} of three markers with equal sides ({named}{more}): an exchange inside one "
            "keeps every distance; where the plate is seen whole in frames near enough, how far it turned tells its "
            "labels apart, but a plate lost whole for longer may come back exchanged")
