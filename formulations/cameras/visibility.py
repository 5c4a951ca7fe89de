"""Occlusion-aware detection probability P_D (Ringer & Lasenby 2002, eq. 8).

P_D(n, c), the probability that camera c detects marker n, is found by tracing the ray from
the marker's (predicted) centre X_n to the camera centre C_c against the body: zero where
the ray passes through a limb, lambda_D (a visible marker's detection rate) where it is
clear, and in between where it passes near a limb's edge ("blurry" edges).

The body is a set of capsules b (a cylinder of radius r_b around the axis segment A_b B_b
with hemispherical caps; A_b = B_b is a sphere), posed per frame by ``visibility_body``.
With delta_b(n, c) the shortest distance between the ray segment X_n C_c and the axis
segment, the ray's clearance of capsule b is

    e_b(n, c) = delta_b(n, c) - r'_b(n),     r'_b(n) = min(r_b, d_b(n) - w),

d_b(n) the distance of X_n from the axis and w the half-width of the blurry edge (below).
A capsule never dims the marker it carries: where the marker's centre lies less than w
outside it (its own limb, or a radius estimated too large), the capsule is shrunk to pass
w under the marker, so a ray leaving the limb outwards keeps clearance w (visible, even
grazing) and a ray going back through the limb dips to about w - d_b (hidden). For a
convex limb this is the exact test, up to the edge.

The edge: the marker is a ball of radius m, so a ray passing within m of a limb's surface
sees it partly covered; with the prediction's own uncertainty sigma the edge's half-width is
w = sqrt(m^2 + sigma^2) (``blur``), and

    P_D(n, c) = lambda_D prod_b S(e_b(n, c) / w),   S(z) = 0 (z <= -1), 1 (z >= 1),
                                                    3 u^2 - 2 u^3 with u = (z + 1) / 2,

a smooth step, monotone in every clearance. Vectorised over markers x cameras x capsules.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.errors import FormulationError

Array = NDArray[np.float64]
TINY = 1e-12


@dataclass(frozen=True)
class Body:
    """Capsules the rays are traced against, in the cameras' world frame (mm).

    Attributes:
        start, end: ``(B, 3)`` axis end points (equal for a sphere).
        radius: ``(B,)`` radius r_b.
    """

    start: Array
    end: Array
    radius: Array

    def __post_init__(self) -> None:
        b = len(self.radius)
        if self.start.shape != (b, 3) or self.end.shape != (b, 3):
            raise FormulationError(f"body: start and end must be ({b}, 3), got {self.start.shape} and {self.end.shape}")
        if not (np.isfinite(self.start).all() and np.isfinite(self.end).all() and (self.radius >= 0).all()):
            raise FormulationError("body: capsule ends must be finite and radii >= 0")


def blur(marker_radius: float, prediction_sigma: float = 0.0) -> float:
    """w = sqrt(m^2 + sigma^2): half-width of a limb's blurry edge (module doc)."""
    return float(np.hypot(marker_radius, prediction_sigma))


def smooth_step(z: Array) -> Array:
    """S(z): 0 below -1, 1 above 1, the cubic 3u^2 - 2u^3 (u = (z + 1) / 2) between."""
    u = np.clip((z + 1.0) / 2.0, 0.0, 1.0)
    step: Array = u * u * (3.0 - 2.0 * u)
    return step


def detection_probability(
    body: Body, markers: Array, centres: Array, lambda_d: float, edge: float,
) -> Array:
    """``(N, C)`` P_D of each marker in each camera (module doc).

    Args:
        body: The posed capsules.
        markers: ``(N, 3)`` marker centres X_n; rows with NaN get NaN.
        centres: ``(C, 3)`` camera centres C_c.
        lambda_d: Detection probability of a marker whose ray is clear, in (0, 1].
        edge: Half-width w of the blurry edge, mm (``blur``: from the marker radius), > 0.
    """
    if not 0.0 < lambda_d <= 1.0 or not edge > 0.0:
        raise FormulationError(f"visibility: need 0 < lambda_D <= 1 and edge > 0, got {lambda_d} and {edge}")
    clearance = ray_clearance(body, markers, centres, edge)
    p: Array = lambda_d * smooth_step(clearance / edge).prod(axis=2)
    known = np.isfinite(np.asarray(markers, dtype=np.float64)).all(axis=1, keepdims=True)
    return np.where(known, p, np.nan)


def ray_clearance(body: Body, markers: Array, centres: Array, edge: float) -> Array:
    """``(N, C, B)`` clearance e_b(n, c) of each ray from each capsule, w = ``edge`` (module doc)."""
    x = np.nan_to_num(np.asarray(markers, dtype=float))[:, None, None, :]
    a, b = body.start[None, None], body.end[None, None]
    delta = segment_distance(x, np.asarray(centres, dtype=float)[None, :, None, :], a, b)
    d_marker = segment_distance(x, x, a, b)[:, 0, :]  # (N, B): ray of length 0
    own = np.minimum(body.radius[None, :], d_marker - edge)
    clearance: Array = delta - own[:, None, :]
    return clearance


def segment_distance(p1: Array, q1: Array, p2: Array, q2: Array) -> Array:
    """Shortest distance between segments p1 q1 and p2 q2, broadcast over leading axes.

    Ericson, Real-Time Collision Detection (2005), Sec. 5.1.9: the closest points
    p1 + s d1 and p2 + t d2 minimise |r + s d1 - t d2|^2 (r = p1 - p2) over [0, 1]^2; the
    unconstrained s is clamped, t follows from s and is clamped, and s is recomputed
    from the clamped t. A point (degenerate segment) takes s = 0 or t = 0, and the other
    parameter follows from it.
    """
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e = _dot(d1, d1), _dot(d2, d2)
    b, c, f = _dot(d1, d2), _dot(d1, r), _dot(d2, r)
    denominator = a * e - b * b
    parallel = denominator <= TINY * np.maximum(a * e, TINY)
    s = np.where(parallel, 0.0, np.clip((b * f - c * e) / np.where(parallel, 1.0, denominator), 0.0, 1.0))
    s = np.where(a <= TINY, 0.0, s)
    t = np.where(e <= TINY, 0.0, (b * s + f) / np.where(e <= TINY, 1.0, e))
    t_clamped = np.clip(t, 0.0, 1.0)
    s_again = np.clip((b * t_clamped - c) / np.where(a <= TINY, 1.0, a), 0.0, 1.0)
    s = np.where(((t != t_clamped) | (e <= TINY)) & (a > TINY), s_again, s)
    gap = r + s[..., None] * d1 - t_clamped[..., None] * d2
    distance: Array = np.sqrt(_dot(gap, gap))
    return distance


def _dot(u: Array, v: Array) -> Array:
    product: Array = np.einsum("...d,...d->...", u, v)
    return product
