"""A joint's rest orientation: how segment b usually sits in segment a's frame.

Two markers of a segment hung from a joint, with the joint centre, make a triangle. When
the markers are about as far from the centre as each other (a wrist's medial and lateral
markers reach the elbow within a few mm), the triangle is nearly isosceles and its two
readings (p on point i and q on j, or crosswise) fit equally well: exchanging the markers
is a half turn about the triangle's axis of symmetry. What tells them apart is how the
segment sits on its parent. With R_a(k), R_b(k) the segments' rotations in the frames
the model was fitted on, the rest orientation is their chordal mean

    Q = argmin_{Q in SO(3)} sum_k |R_a(k)^T R_b(k) - Q|_F^2 = U diag(1, 1, det(U V^T)) V^T,

U S V^T the SVD of sum_k R_a(k)^T R_b(k). A reading of b with rotation R_b, its parent a
posed at R_a, is then turned from rest by the angle of R_a^T R_b Q^T. The true reading is
turned by the joint's motion (an elbow's flexion); the exchanged one by that composed
with a half turn, close to 180 degrees for any motion about an axis across the segment.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def rest_rotation(rotation_a: Array, rotation_b: Array) -> list[list[float]] | None:
    """Q of the module doc from ``(K, 3, 3)`` rotations (NaN where a segment has no pose);
    None when no frame poses both."""
    both = np.isfinite(rotation_a).all(axis=(1, 2)) & np.isfinite(rotation_b).all(axis=(1, 2))
    if not both.any():
        return None
    total = np.einsum("kji,kjl->il", rotation_a[both], rotation_b[both])
    u, _, vt = np.linalg.svd(total)
    q = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
    return [[round(float(v), 4) for v in row] for row in q]  # 1e-4: a hundredth of a degree


def turned_from(usual: Array, rotation: Array) -> float:
    """Radians between a segment's ``rotation`` and ``usual``, R_a Q: the angle of R_b (R_a Q)^T,
    which is that of R_a^T R_b Q^T (module doc)."""
    turn = rotation @ usual.T
    return float(np.arccos(np.clip((np.trace(turn) - 1.0) / 2.0, -1.0, 1.0)))
