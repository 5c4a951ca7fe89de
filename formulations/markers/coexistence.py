"""Coexistence: a point track seen beside a marker is not that marker.

A marker unseen for u frames was last seen at frame t - u, on the point a it took then
(``MarkerState.seen_at``; not its anchor, which a rigid fit carries). A point of the
template frame t that no marker holds is followed back frame by frame (``back_tracks``:
constant velocity, as the unnamed tracks are followed forward, ``markers.unnamed``). If
its track reaches frame t - u at a point other than a, that track and the marker were two
objects at once: whatever the point is (a marker the labeled frame does not name, another
lost marker, a steady reflection), it is not the marker's. The test trusts the marker's
last label, so its caller leaves out markers whose label is doubtful or whose last point
was held for fewer than ``SURE_STREAK`` frames (``seen_at`` NaN).

Shape alone cannot tell it: on real 03_rolling (from frame 562) LR_TAM, hidden at 892, was
handed at template 904 the point of LR_FAL, a marker absent from the labeled frame whose
point had been followed unlabeled since frame 615 beside LR_TAM's own, 108 mm away; both
sit on the shank, so LR_FAL's point fits LR_TAM's neighbour distances, and LR_TAM kept it
to the end of the take.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

SAME_POINT_MM = 1e-3  # the track passes through the marker's own point there


def back_tracks(points: np.ndarray, earlier: list[np.ndarray], reach: float, link_radius: float) -> np.ndarray:
    """``(P, L, 3)``: the track of each of ``points`` (``(P, 3)``, template frame) in each of
    the ``L`` frames ``earlier`` (``earlier[0]`` the frame before the template, going back),
    NaN from where it breaks.

    The first step back links to the nearest point within ``reach`` (no velocity yet); each
    later one to the nearest within ``link_radius`` of where the track's last step puts it;
    either only where no other point is within ``link_radius`` more (``_unambiguous``).
    """
    track = np.full((len(points), len(earlier), 3), np.nan)
    rows = np.arange(len(points))  # the tracks still followed, and where each one is
    last = np.array(points, float).reshape(-1, 3)
    step, radius = np.zeros_like(last), reach  # no velocity yet: the first step is predicted where the track is
    for k, frame in enumerate(earlier):
        if not len(rows) or not len(frame):
            break
        nearest, found = _unambiguous(cdist(last + step, frame), radius, link_radius)
        rows, point = rows[found], frame[nearest[found]]
        step, last, radius = point - last[found], point, link_radius
        track[rows, k] = point
    return track


def _unambiguous(distance: np.ndarray, radius: float, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``distance`` (tracks x points), the nearest point, and whether it links: within
    ``radius``, and no other point within ``margin`` more. Where two points could
    continue a track, following either may jump to another marker's track (fast gloves 30 mm
    apart), and the test would then bar a marker from its own point."""
    if distance.shape[1] == 0:
        return np.zeros(len(distance), int), np.zeros(len(distance), bool)
    nearest = distance.argmin(axis=1)
    two = np.partition(distance, 1, axis=1)[:, :2] if distance.shape[1] > 1 else np.c_[distance, np.full(len(distance), np.inf)]
    return nearest, (two[:, 0] <= radius) & (two[:, 1] > two[:, 0] + margin)


def coexisted(unseen: np.ndarray, seen_at: np.ndarray, tracks: np.ndarray) -> np.ndarray:
    """``(N, P)`` True where the track of point p (``back_tracks``) was somewhere other than
    marker n's point ``seen_at`` in the frame it was last seen, ``unseen[n]`` frames back."""
    if tracks.shape[1] == 0:  # followed back no frame: nothing was seen beside anyone
        return np.zeros((len(unseen), len(tracks)), bool)
    back = np.asarray(unseen, int) - 1  # index into ``tracks``' frames: 0 is one frame back
    reached = (back >= 0) & (back < tracks.shape[1])
    there = tracks[:, np.clip(back, 0, tracks.shape[1] - 1)].transpose(1, 0, 2)
    off = np.linalg.norm(there - seen_at[:, None], axis=2)
    return np.asarray(reached[:, None] & np.isfinite(off) & (off > SAME_POINT_MM))
