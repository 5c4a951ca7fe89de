"""Markers that move more per frame than their neighbours are apart: a warning for the take.

A marker's gate is centred on its prediction. With little motion seen, or motion that
turns within a frame, the prediction is close to the last position, and a marker whose
step s is more than half the distance d to its nearest neighbour then lies nearer that
neighbour's last position than its own: tight rigid clusters on fast segments (a
wheelchair racer's 3-marker clusters 30 mm apart moving 28 mm a frame) swap labels no
matter how the window is solved. The take is read from its labeled result:

    s_n = median over frames of ||x_n(f+1) - x_n(f)||   (both frames labeled)
    d_n = median over frames of min_{j != n} ||x_n(f) - x_j(f)||   (both labeled)

and a marker is flagged when s_n > FAST_RATIO * d_n. A marker on the same position as
another (a copied column, ``coincident``) is not its neighbour.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from service.labeling.coincident import COINCIDENT_MM, sampled_distances

FAST_RATIO = 0.5  # s > d / 2: the last position is nearer the neighbour's than the marker's own
LISTED = 4  # markers named in the warning line


@dataclass(frozen=True)
class FastMarker:
    """A marker whose median step per frame exceeds ``FAST_RATIO`` of its neighbour distance (mm)."""

    marker: str
    step_mm: float
    neighbour_mm: float
    neighbour: str


def fast_markers(names: list[str], positions: np.ndarray) -> list[FastMarker]:
    """The flagged markers of labeled ``positions`` ``(F, N, 3)`` (mm, NaN unlabeled), fastest relative first."""
    if len(positions) < 2 or len(names) < 2:
        return []
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=2)  # (F-1, N), NaN unless both labeled
    step = _median_or_nan(steps)
    apart = sampled_distances(positions)  # (S, N, N)
    apart[:, np.arange(len(names)), np.arange(len(names))] = np.nan
    apart[apart < COINCIDENT_MM] = np.nan  # a copied column is no neighbour (``coincident``)
    nearest = np.where(np.isfinite(apart), apart, np.inf)
    closest = np.argmin(nearest, axis=2)  # (S, N)
    distance = np.min(nearest, axis=2)
    distance[~np.isfinite(distance)] = np.nan
    spacing = _median_or_nan(distance)
    flagged = np.flatnonzero(step > FAST_RATIO * spacing)  # NaN compares False: unknowns are not flagged
    found = [
        FastMarker(names[n], float(step[n]), float(spacing[n]), names[_most_common(closest[np.isfinite(distance[:, n]), n])])
        for n in flagged
    ]
    return sorted(found, key=lambda f: f.neighbour_mm / f.step_mm)


def fast_motion_warning(fast: list[FastMarker]) -> str | None:
    """One line naming the flagged markers (the first ``LISTED``), or None."""
    if not fast:
        return None
    named = ", ".join(
        f"{f.marker} {f.step_mm:.0f} mm/frame, {f.neighbour_mm:.0f} mm from {f.neighbour}" for f in fast[:LISTED]
    )
    more = f" and {len(fast) - LISTED} more" if len(fast) > LISTED else ""
    return (f"warning: {len(fast)} markers move more per frame than half the distance to their nearest "
            f"neighbour (medians: {named}{more}); their labels may swap at this frame rate")


def _median_or_nan(values: np.ndarray) -> np.ndarray:
    """Column medians over finite entries; NaN for a column with none (no warning from numpy)."""
    out = np.full(values.shape[1], np.nan)
    seen = np.isfinite(values).any(axis=0)
    out[seen] = np.nanmedian(values[:, seen], axis=0)
    return out


def _most_common(indices: np.ndarray) -> int:
    return int(np.bincount(indices).argmax())
