"""How well a calibrated camera shows a marker: projected size, visibility, viewing angle.

For a marker at X (world), camera b with focal length f_b (pixels), rotation R_b,
translation t_b and centre C_b = -R_b^T t_b:

- projected size: a sphere of diameter D at depth z_b = (R_b X + t_b)_3 images to
  about f_b D / z_b pixels. D is the same in every camera and cancels in the relative
  costs (``costs``), so s_b = f_b / z_b; s_b = 0 behind the camera (z_b <= 0) or when X
  projects outside the image.
- visibility: v_b in [0, 1], the probability that camera b detects the marker: the
  occlusion-aware P_D of ``formulations.cameras.visibility.detection_probability``
  (Ringer & Lasenby 2002, eq. 8), or whether the marker was detected in camera b (1 or
  0), which is what the service passes today.
- viewing angle: a marker sits on the skin, facing away from the body. Its outward
  normal is estimated as n = (X - X_bar) / |X - X_bar|, X_bar the centroid of the
  frame's markers, and the camera sees it at the angle theta_b with
  cos theta_b = n . (C_b - X) / |C_b - X|: head-on 1, grazing 0, from behind -1.
  Where n is undefined (a lone marker, or one at the centroid) the factor is 1.

    q_b = v_b s_b (1 + cos theta_b) / 2                                          (1)

Every factor is >= 0, so q_b = 0 exactly when camera b cannot show the marker.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from formulations.cameras.camera import Camera
from formulations.errors import FormulationError


def marker_quality(
    positions: npt.ArrayLike, visibility: npt.ArrayLike, cameras: Sequence[Camera],
) -> npt.NDArray[np.float64]:
    """``(F, K, M)`` quality (1) of each of M cameras for each of K markers in F frames.

    Args:
        positions: ``(F, K, 3)`` marker positions in the cameras' world unit, NaN where
            unknown (quality 0 there).
        visibility: ``(F, K, M)`` detection probability in [0, 1] (or 0/1: detected).
        cameras: The M calibrated cameras.

    Raises:
        FormulationError: shapes that do not agree, or a visibility outside [0, 1].
    """
    x = np.asarray(positions, dtype=float)
    v = np.asarray(visibility, dtype=float)
    if x.ndim != 3 or x.shape[2] != 3 or v.shape != x.shape[:2] + (len(cameras),):
        raise FormulationError(
            f"best view: positions (F, K, 3) and visibility (F, K, {len(cameras)}) expected, got {x.shape} and {v.shape}"
        )
    if not ((v >= 0) & (v <= 1)).all():
        raise FormulationError("best view: visibility must lie in [0, 1]")
    normal = _outward_normals(x)
    quality = np.zeros(v.shape)
    flat = x.reshape(-1, 3)
    known = np.isfinite(flat).all(axis=1)
    for b, camera in enumerate(cameras):
        depth = flat @ camera.R[2] + camera.t[2]
        shown = known & (depth > 0)
        shown[shown] = camera.in_image(camera.project(flat[shown]))
        size = np.where(shown, camera.focal / np.where(shown, depth, 1.0), 0.0)
        towards = camera.centre - flat
        with np.errstate(invalid="ignore", divide="ignore"):
            cosine = np.einsum("pd,pd->p", normal.reshape(-1, 3), towards) / np.linalg.norm(towards, axis=1)
        facing = np.where(np.isfinite(cosine), 0.5 * (1.0 + cosine), 1.0)
        quality[..., b] = v[..., b] * (size * facing).reshape(v.shape[:2])
    return quality


def _outward_normals(x: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """``(F, K, 3)`` unit vectors from each frame's marker centroid to each marker, NaN where undefined."""
    known = np.isfinite(x).all(axis=2, keepdims=True)
    count = known.sum(axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        centroid = np.where(known, x, 0.0).sum(axis=1, keepdims=True) / count
        away = x - centroid
        length = np.linalg.norm(away, axis=2, keepdims=True)
        normal: npt.NDArray[np.float64] = np.where((count > 1) & (length > 0), away / length, np.nan)
    return normal
