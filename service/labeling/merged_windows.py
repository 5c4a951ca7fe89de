"""One pass's windows with some markers' labels taken from another pass of the same take.

``formulations.markers.pass_merge`` says, per marker, which of two passes to keep; both
passes label the same windows, so each window is merged column by column: the markers
taken from the other pass bring their point indices, fills, confidences and their rows of
the marker state at the window's end. The window's certificate and timings stay those of
the pass the rest of the markers come from (the merged labels are no LP's optimum; the
summary names how many markers came from the other pass).
"""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np

from formulations.markers.state import MarkerState
from service.labeling.outcome import WindowOutcome
from service.labeling.stats import doubtful_labels


def merged_windows(mine: list[WindowOutcome], theirs: list[WindowOutcome], taken: np.ndarray) -> list[WindowOutcome]:
    """``mine`` with the markers ``taken`` (``(N,)`` bool) labeled as in ``theirs``."""
    if not taken.any():
        return mine
    return [_merged(a, b, taken) for a, b in zip(mine, theirs, strict=True)]


def _merged(mine: WindowOutcome, theirs: WindowOutcome, taken: np.ndarray) -> WindowOutcome:
    """One window: frames x markers arrays by column, per-marker arrays by row."""
    state = MarkerState(**{f.name: _pick(getattr(mine.state, f.name), getattr(theirs.state, f.name), taken, 0)
                           for f in fields(MarkerState)})
    point_index = _pick(mine.point_index, theirs.point_index, taken, 1)
    confidence = _optional(mine.confidence, theirs.confidence, taken, 1)
    doubtful = mine.stats.doubtful if confidence is None else int(doubtful_labels(confidence, point_index < 0).sum())
    return replace(
        mine, point_index=point_index, filled=_pick(mine.filled, theirs.filled, taken, 1), state=state,
        confidence=confidence, carry=_optional(mine.carry, theirs.carry, taken, 0),
        trusted_mean=_optional(mine.trusted_mean, theirs.trusted_mean, taken, 0),
        trusted_var=_optional(mine.trusted_var, theirs.trusted_var, taken, 0), stats=replace(mine.stats, doubtful=doubtful),
    )


def _pick(a: np.ndarray, b: np.ndarray, taken: np.ndarray, axis: int) -> np.ndarray:
    """``a`` with the entries of the ``taken`` markers (along ``axis``) from ``b``."""
    shape = [1] * a.ndim
    shape[axis] = -1
    picked: np.ndarray = np.where(taken.reshape(shape), b, a)
    return picked


def _optional(a: np.ndarray | None, b: np.ndarray | None, taken: np.ndarray, axis: int) -> np.ndarray | None:
    """``_pick`` where both windows carry the array (windows stored before it existed do not)."""
    return a if a is None or b is None else _pick(a, b, taken, axis)
