"""One pass's windows with some markers' labels taken from another pass of the same take.

``formulations.markers.pass_merge`` says, per frame and marker, which of two passes to keep;
both passes label the same windows, so each window is merged label by label: the labels
taken from the other pass bring their point indices, fills and confidences, and a marker
taken in the window's last frame its rows of the marker state at the window's end. The
window's certificate and timings stay those of the pass the rest of the markers come from
(the merged labels are no LP's optimum; the summary names how many markers came from the
other pass).
"""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np

from formulations.markers.state import MarkerState
from service.labeling.outcome import WindowOutcome
from service.labeling.stats import doubtful_labels


def merged_windows(mine: list[WindowOutcome], theirs: list[WindowOutcome], taken: np.ndarray) -> list[WindowOutcome]:
    """``mine`` with the labels ``taken`` (``(F, N)`` bool over the take's frames) as in ``theirs``."""
    if not taken.any():
        return mine
    return [_merged(a, b, taken[a.stats.template + 1: a.stats.last + 1]) for a, b in zip(mine, theirs, strict=True)]


def _merged(mine: WindowOutcome, theirs: WindowOutcome, taken: np.ndarray) -> WindowOutcome:
    """One window, ``taken`` its ``(M, N)`` labels to take: frames x markers arrays label by
    label, per-marker arrays by the marker's last frame."""
    if not taken.any():
        return mine
    last = taken[-1]
    state = MarkerState(**{f.name: _pick(getattr(mine.state, f.name), getattr(theirs.state, f.name), last)
                           for f in fields(MarkerState)})
    point_index = _pick(mine.point_index, theirs.point_index, taken)
    confidence = _optional(mine.confidence, theirs.confidence, taken)
    doubtful = mine.stats.doubtful if confidence is None else int(doubtful_labels(confidence, point_index < 0).sum())
    return replace(
        mine, point_index=point_index, filled=_pick(mine.filled, theirs.filled, taken), state=state,
        confidence=confidence, carry=_optional(mine.carry, theirs.carry, last),
        trusted_mean=_optional(mine.trusted_mean, theirs.trusted_mean, last),
        trusted_var=_optional(mine.trusted_var, theirs.trusted_var, last), stats=replace(mine.stats, doubtful=doubtful),
    )


def _pick(a: np.ndarray, b: np.ndarray, taken: np.ndarray) -> np.ndarray:
    """``a`` with the entries ``taken`` (its leading axes) from ``b``."""
    picked: np.ndarray = np.where(taken.reshape(taken.shape + (1,) * (a.ndim - taken.ndim)), b, a)
    return picked


def _optional(a: np.ndarray | None, b: np.ndarray | None, taken: np.ndarray) -> np.ndarray | None:
    """``_pick`` where both windows carry the array (windows stored before it existed do not)."""
    return a if a is None or b is None else _pick(a, b, taken)
