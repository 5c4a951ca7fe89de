"""A labeling with the exchanges the labeled first frame finds over the whole take given
back (``formulations.markers.take_exchange``).

An exchanged label is one the windows read otherwise: it is given back, and marked doubtful
(``EXCHANGED_CONFIDENCE``) so that the summary counts it and a user looks at it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.markers.state import MarkerState
from formulations.markers.take_exchange import TakeExchange, take_exchanges
from service.io.recording import LabeledTrajectories

EXCHANGED_CONFIDENCE = 0.5  # the windows and the first frame's shape read these labels otherwise


def exchanged_back(labels: LabeledTrajectories, first: MarkerState) -> tuple[LabeledTrajectories, list[TakeExchange]]:
    """``labels`` with each exchange of ``take_exchanges`` applied to every per-label array,
    and the exchanges."""
    predicted = labels.filled if labels.filled.size else None
    exchanges = take_exchanges(labels.positions, first.position, first.neighbours, predicted)
    if not exchanges:
        return labels, exchanges
    arrays = {name: getattr(labels, name).copy() for name in ("positions", "occluded", "point_index", "filled", "confidence")
              if getattr(labels, name).size}
    for e in exchanges:
        for values in arrays.values():
            values[e.start : e.stop, [e.a, e.b]] = values[e.start : e.stop, [e.b, e.a]]
        if "confidence" in arrays:
            arrays["confidence"][e.start : e.stop, [e.a, e.b]] = np.fmin(
                arrays["confidence"][e.start : e.stop, [e.a, e.b]], EXCHANGED_CONFIDENCE)
    return replace(labels, **arrays), exchanges


def exchange_summary(exchanges: list[TakeExchange], names: list[str]) -> list[dict]:
    """Each exchange as ``{"markers": [a, b], "frames": [start, stop]}`` (frames from 0, stop
    exclusive), for a summary."""
    return [{"markers": [names[e.a], names[e.b]], "frames": [e.start, e.stop]} for e in exchanges]
