"""How well a camera shows an object seen as a bounding box: its size and its truncation.

Jiang et al. (Sec. IV-B) measure a view by the size of the object's box. A box cut by
the image border shows only part of the object; with the box (left, top, width, height)
in pixels and the image [0, W] x [0, H], the truncated fraction is

    tau = 1 - area(box ∩ image) / area(box)

and the quality is the visible area discounted once more by what is cut off,

    q = area(box ∩ image) (1 - tau) = area(box) (1 - tau)^2,

so half an object is worth less than a whole one of the same visible size (a view of
a whole person beats a view of a larger torso). A missing box (NaN) has q = 0.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from formulations.errors import FormulationError


def box_truncation(boxes: npt.ArrayLike, image_size: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``(...)`` fraction tau of each ``(..., 4)`` box (left, top, width, height) outside the image.

    ``image_size`` is ``(width, height)``, or ``(..., 2)`` broadcasting with the boxes
    (one size per camera). NaN boxes give NaN.

    Raises:
        FormulationError: a box with a negative width or height.
    """
    b = _boxes(boxes)
    size = np.asarray(image_size, dtype=float)
    left, top = np.maximum(b[..., 0], 0.0), np.maximum(b[..., 1], 0.0)
    right = np.minimum(b[..., 0] + b[..., 2], size[..., 0])
    bottom = np.minimum(b[..., 1] + b[..., 3], size[..., 1])
    inside = np.maximum(right - left, 0.0) * np.maximum(bottom - top, 0.0)
    area = b[..., 2] * b[..., 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        truncation: npt.NDArray[np.float64] = np.where(area > 0, 1.0 - inside / area, 1.0)
    truncation[np.isnan(area)] = np.nan
    return truncation


def box_quality(boxes: npt.ArrayLike, image_size: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``(...)`` quality q = area (1 - tau)^2 of ``(..., 4)`` boxes, 0 where a box is NaN (missing)."""
    b = _boxes(boxes)
    kept = 1.0 - box_truncation(b, image_size)
    quality = b[..., 2] * b[..., 3] * kept**2
    return np.nan_to_num(quality, nan=0.0)


def _boxes(boxes: npt.ArrayLike) -> npt.NDArray[np.float64]:
    b = np.asarray(boxes, dtype=float)
    if b.shape[-1:] != (4,):
        raise FormulationError(f"best view: boxes must be (..., 4) left, top, width, height, got shape {b.shape}")
    if (b[..., 2:] < 0).any():
        raise FormulationError("best view: a box has a negative width or height")
    return b
