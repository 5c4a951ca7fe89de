"""Edges and foreground as a weighting function (Section 3.2, eq. 3-5, Fig. 2).

For a posed body and a camera with centre o, each cone from A to B with radii (r_A, r_B) is
seen edge-on along its occluding contours: with n the unit normal to both the axis B - A and
the viewing direction (A + B) / 2 - o, the contours are A + t (B - A) +- r(t) n, r(t) =
r_A + t (r_B - r_A). ``contour`` sites per contour line sample the edge map p^e there, and
a grid of ``region`` sites along the axis times three across it (s in {-2/3, 0, 2/3}) samples
the foreground map p^r inside the cone's projection. Then, per camera c,

    Sigma^e_c = (1 / N^e) sum_i (1 - p^e_i)^2,   Sigma^r_c = (1 / N^r) sum_i (1 - p^r_i)^2   (eq. 3)

and E = sum_c (Sigma^e_c + Sigma^r_c), w = exp(-E) (eq. 5). Sites outside the image sample 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.cameras.rig import Rig
from formulations.pose.body import BodyModel
from formulations.pose.kinematics import Posed
from formulations.pose.rotation import Array

ACROSS = np.array([-2.0 / 3.0, 0.0, 2.0 / 3.0])


def cone_sites(model: BodyModel, posed: Posed, centre: Array, contour: int, region: int) -> tuple[Array, Array]:
    """``(N, cones * 2 * contour, 3)`` contour sites and ``(N, cones * 3 * region, 3)`` region sites seen from ``centre``."""
    starts = posed.positions[:, [c.start for c in model.cones]]
    ends = posed.positions[:, [c.end for c in model.cones]]
    radii = np.array([c.radii for c in model.cones], dtype=float)  # (cones, 2)
    axis = ends - starts
    normal = np.cross(axis, 0.5 * (starts + ends) - centre)
    normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-12)

    def sites(t: Array, across: Array) -> Array:
        radius = radii[:, 0, None] + t[None] * (radii[:, 1] - radii[:, 0])[:, None]  # (cones, T)
        along = starts[:, :, None] + t[None, None, :, None] * axis[:, :, None]  # (N, cones, T, 3)
        side = across[None, None, None, :, None] * (radius[None, :, :, None, None] * normal[:, :, None, None, :])
        points: Array = (along[:, :, :, None] + side).reshape(len(starts), -1, 3)
        return points

    return sites((np.arange(contour) + 0.5) / contour, np.array([-1.0, 1.0])), sites((np.arange(region) + 0.5) / region, ACROSS)


def sample(image: Array, pixels: Array) -> Array:
    """``image`` at the nearest pixel of each ``(..., 2)`` (x, y); 0 outside the image."""
    height, width = image.shape
    column = np.rint(pixels[..., 0]).astype(int)
    row = np.rint(pixels[..., 1]).astype(int)
    inside = (column >= 0) & (column < width) & (row >= 0) & (row < height)
    values = np.zeros(pixels.shape[:-1])
    values[inside] = image[row[inside], column[inside]]
    return values


@dataclass(frozen=True)
class SilhouetteMeasurement:
    """One frame's edge maps and foreground maps ``(C, H, W)`` in [0, 1] for a rig's cameras."""

    rig: Rig
    model: BodyModel
    edges: Array
    foreground: Array
    contour: int = 8
    region: int = 5

    @property
    def empty(self) -> bool:
        return not bool((self.foreground > 0).any())

    def energy(self, posed: Posed) -> Array:
        """``(N,)`` E(X) of the module doc (eq. 3-5)."""
        total = np.zeros(len(posed.positions))
        for c, camera in enumerate(self.rig.cameras):
            contour, region = cone_sites(self.model, posed, camera.centre, self.contour, self.region)
            count = len(total)
            edge = sample(self.edges[c], camera.project(contour.reshape(-1, 3)).reshape(count, -1, 2))
            inside = sample(self.foreground[c], camera.project(region.reshape(-1, 3)).reshape(count, -1, 2))
            total += ((1.0 - edge) ** 2).mean(axis=1) + ((1.0 - inside) ** 2).mean(axis=1)
        return total
