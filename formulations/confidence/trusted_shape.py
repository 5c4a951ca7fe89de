"""Lifting a doubt: a doubtful label judged by the shape its marker had when last trusted.

A label's confidence is carried from window to window (``service.labeling.confidence``):
once a marker's identity is doubtful, later windows, which follow the track they were given,
cannot tell whether it is right. The learned shape cannot tell either: the distance
statistics learn a wrong label's shape within about 1 / rate frames
(``MarkerState.advance``), after which a wrong label fits as well as a right one. So a
doubt, right or wrong, stayed to the end of the take (on the rolling and tennis takes 80 %
of the doubtful labels were right ones, flagged for hundreds of frames).

The shape a marker had when its label was last trusted was learned before the doubt arose,
so it is evidence the doubt has not touched. ``TrustedShape`` keeps, per marker, the distance
statistics of its last trusted window; ``confirmed`` judges a doubtful marker by them:
p(m) of ``shape.shape_identity`` (its own point against an exchange with any seen neighbour
or a lost marker's point), with the learned statistics replaced by the trusted ones.

Only firm evidence judges: at least ``min_rigid`` of the marker's neighbours that are rigid
with it (trusted distance s.d. at most ``max_sd_mm``) must be seen and vouch for it
(``ShapeReacquisition``'s rule for judging a point by its shape); otherwise nothing is said
and the doubt stays. A neighbour vouches when it is trusted, or doubtful and confirmed
itself on firm evidence (``confirmed``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from formulations.confidence.shape import shape_identity
from formulations.markers.shape_reacquire import SHAPE_REACQUISITION, ShapeReacquisition
from formulations.markers.state import MarkerState

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]


@dataclass(frozen=True)
class TrustedShape:
    """``(N, K)`` each marker's neighbour distance means and variances (mm, mm^2), as learned
    at the end of the last window in which its label was trusted (neighbours: ``MarkerState``'s).

    A marker not yet seen has no trusted shape (NaN rows): what its statistics hold then
    is a guess (a subject model's start puts unnamed markers at the body's centroid), not
    a shape learned from its own point. It gets one at the first window that ends with it
    seen and trusted.
    """

    distance_mean: Array
    distance_var: Array

    @classmethod
    def of(cls, state: MarkerState) -> TrustedShape:
        """The shapes of the markers seen at ``state``; none for the others."""
        seen = state.visible[:, None]
        return cls(np.where(seen, state.distance_mean, np.nan), np.where(seen, state.distance_var, np.nan))

    @property
    def known(self) -> Mask:
        """``(N,)`` markers that have a trusted shape."""
        known: Mask = np.asarray(np.isfinite(self.distance_mean).all(axis=1))
        return known

    def put_in(self, state: MarkerState, rows: Mask) -> MarkerState:
        """``state`` with the trusted shapes of the ``rows`` markers that have one."""
        take = (rows & self.known)[:, None]
        return replace(
            state, distance_mean=np.where(take, self.distance_mean, state.distance_mean),
            distance_var=np.where(take, self.distance_var, state.distance_var),
        )

    def updated(self, end: MarkerState, trusted: Mask) -> TrustedShape:
        """The shapes of ``trusted`` markers taken from ``end`` (a first one only where seen
        there); the others' kept as they were."""
        take = (trusted & (self.known | end.visible))[:, None]
        return TrustedShape(
            np.where(take, end.distance_mean, self.distance_mean),
            np.where(take, end.distance_var, self.distance_var),
        )


def confirmed(
    shape: TrustedShape, end: MarkerState, doubtful: NDArray[np.intp], trusted: Mask, sure: float,
    settings: ShapeReacquisition = SHAPE_REACQUISITION,
) -> Array:
    """``(D,)`` p(m) for the seen markers ``doubtful`` judged by their trusted shape; NaN where
    the evidence is not firm (module doc).

    A doubtful marker whose own p(m) is at least ``sure`` vouches for its neighbours like a
    trusted one, as long as it is firm itself: a limb doubted as a whole (every marker of the
    tennis serve's forearm after one bad strike) has no trusted neighbour, yet an exchange
    inside it breaks its distances to the rest. The vouchers are the largest such set (a
    fixed point: drop every voucher not firm under the others until none is).

    Args:
        shape: The trusted shapes.
        end: The state at the window's last frame (positions, who is seen).
        doubtful: Markers seen at ``end`` whose labels are doubtful.
        trusted: ``(N,)`` markers whose labels are trusted now.
        sure: The p(m) at which a doubtful marker vouches for others.
    """
    neighbours = end.neighbours[doubtful]
    rigid = shape.distance_var[doubtful] <= settings.max_sd_mm**2  # False on a NaN row: no shape, no judgement
    # Partners without a trusted shape are judged by what they have learned.
    reference = shape.put_in(end, np.ones(len(end.position), bool))
    probability = shape_identity(reference, end, doubtful)
    rigid_seen = rigid & end.visible[neighbours]
    vouching = trusted.copy()
    vouching[doubtful] = probability >= sure
    while True:
        firm = (rigid_seen & vouching[neighbours]).sum(axis=1) >= settings.min_rigid
        lapsed = vouching[doubtful] & ~firm
        if not lapsed.any():
            return np.where(firm, probability, np.nan)
        vouching[doubtful[lapsed]] = False
