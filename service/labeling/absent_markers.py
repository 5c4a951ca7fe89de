"""Markers a relabel leaves out (absent in its labeled frame) put back into its output,
missing in every frame: a relabeled file holds no label markerflow did not give, and a
copy of a C3D input clears their points over the labeled span rather than keep the input's."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from service.io.recording import LabeledTrajectories


def absent_warning(absent: list[str], start: int) -> str | None:
    """The line naming the markers a relabel from frame ``start`` leaves out, or None."""
    if not absent:
        return None
    markers = f"{len(absent)} marker{'s' if len(absent) > 1 else ''}"
    return (f"warning: {markers} absent at frame {start}, not labeled (written missing): "
            f"{', '.join(absent[:12])}{' ...' if len(absent) > 12 else ''}")


def with_absent(
    result: LabeledTrajectories, names: list[str], positions: np.ndarray | None = None,
) -> LabeledTrajectories:
    """``result`` with markers ``names`` appended, occluded in every frame: written as missing,
    so a relabeled file holds no label that markerflow did not give. With ``positions``
    ``(frames, markers, 3)`` mm they hold those instead, occluded where NaN (``carried_markers``)."""
    if not names:
        return result
    frames, extra = result.n_frames, len(names)
    held = np.full((frames, extra, 3), np.nan) if positions is None else np.asarray(positions, float)

    def widened(values: np.ndarray, fill: float | int) -> np.ndarray:
        if values.size == 0:
            return values
        return np.concatenate([values, np.full((frames, extra, *values.shape[2:]), fill, dtype=values.dtype)], axis=1)

    return replace(
        result, names=[*result.names, *names], positions=np.concatenate([result.positions, held], axis=1),
        occluded=np.concatenate([result.occluded, ~np.isfinite(held).all(axis=2)], axis=1),
        point_index=widened(result.point_index, -1),
        filled=widened(result.filled, np.nan), best_view=widened(result.best_view, -1),
        confidence=widened(result.confidence, np.nan),
    )


PER_MARKER = ("positions", "occluded", "point_index", "filled", "best_view", "confidence")


def in_order(result: LabeledTrajectories, order: list[str]) -> LabeledTrajectories:
    """``result``'s markers in ``order``'s column order, any it has that ``order`` lacks after
    them: a relabel's output keeps the input's columns where they were (the absent markers
    were appended last, and a table read by column position moved)."""
    rank = {name: i for i, name in enumerate(order)}
    index = sorted(range(len(result.names)), key=lambda m: rank.get(result.names[m], len(order) + m))
    if index == list(range(len(result.names))):
        return result
    arrays = {name: getattr(result, name)[:, index] for name in PER_MARKER if getattr(result, name).size}
    return replace(result, names=[result.names[m] for m in index], **arrays)
