"""Box geometry: corners, intersection over union, the paper's two overlap measures.

A box is held as its corners ``(x1, y1, x2, y2)`` (top-left, bottom-right), Jiang's 4-vector
location p (Sec. II-C). MOTChallenge files hold ``(left, top, width, height)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def corners(ltwh: Array) -> Array:
    """``(K, 4)`` left, top, width, height -> ``(K, 4)`` x1, y1, x2, y2."""
    box = np.asarray(ltwh, dtype=float).reshape(-1, 4)
    return np.concatenate([box[:, :2], box[:, :2] + box[:, 2:]], axis=1)


def ltwh(corner: Array) -> Array:
    """Inverse of ``corners``."""
    box = np.asarray(corner, dtype=float).reshape(-1, 4)
    return np.concatenate([box[:, :2], box[:, 2:] - box[:, :2]], axis=1)


def area(corner: Array) -> Array:
    size = np.clip(corner[..., 2:] - corner[..., :2], 0.0, None)
    result: Array = size[..., 0] * size[..., 1]
    return result


def intersection(a: Array, b: Array) -> Array:
    """``(A, B)`` intersection areas of every box of ``a`` with every box of ``b``."""
    low = np.maximum(a[:, None, :2], b[None, :, :2])
    high = np.minimum(a[:, None, 2:], b[None, :, 2:])
    size = np.clip(high - low, 0.0, None)
    result: Array = size[..., 0] * size[..., 1]
    return result


def iou(a: Array, b: Array) -> Array:
    """``(A, B)`` intersection over union."""
    inter = intersection(a, b)
    union = area(a)[:, None] + area(b)[None, :] - inter
    result: Array = np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)
    return result


def overlap_ratio(a: Array, b: Array) -> Array:
    """``(A, B)`` intersection over the mean of the two areas (Jiang Sec. II-B, first measure).

    1 for identical boxes; 2/3 when one box holds the other and is twice its area.
    """
    inter = intersection(a, b)
    mean = 0.5 * (area(a)[:, None] + area(b)[None, :])
    result: Array = np.divide(inter, mean, out=np.zeros_like(inter), where=mean > 0)
    return result


def corner_distance(a: Array, b: Array) -> Array:
    """``(A, B)`` total city-block distance of the 4 corners (Jiang Sec. II-B, second measure).

    Summed over the corners (x1,y1), (x2,y1), (x1,y2), (x2,y2): each of the four
    coordinate differences |dx1|, |dy1|, |dx2|, |dy2| enters twice.
    """
    result: Array = 2.0 * np.abs(a[:, None, :] - b[None, :, :]).sum(axis=2)
    return result


def height(corner: Array) -> Array:
    result: Array = corner[..., 3] - corner[..., 1]
    return result


def centre(corner: Array) -> Array:
    result: Array = 0.5 * (corner[..., :2] + corner[..., 2:])
    return result
