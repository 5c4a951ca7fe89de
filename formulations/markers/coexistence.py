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

from bisect import bisect_left
from collections.abc import Sequence

import numpy as np
from scipy.spatial.distance import cdist

SAME_POINT_MM = 1e-3  # the track passes through the marker's own point there


class BackLinks:
    """Follows template points back through one take's ``frames`` (``back_tracks``).

    Every window follows its free points back over frames an earlier window's tracks already
    crossed (on 03_rolling from frame 562, some 900 frames back through one unnamed track), and
    only the radii its links are judged by change from window to window. So each link keeps,
    per frame and predicted position, all its test reads: the nearest point and the two
    smallest distances. A later track predicting the same position there (the same floats:
    the same points and the same arithmetic) reads them instead of measuring them again.
    The frames before the deepest one a window follows are let go: later windows, their
    markers lost since no earlier, seldom reach them (and measure again when they do).
    """

    def __init__(self, frames: Sequence[np.ndarray]) -> None:
        self.frames = frames
        self._empty = [frame for frame, points in enumerate(frames) if not len(points)]  # where every track breaks
        self._links: dict[int, dict[tuple[float, ...], tuple[tuple[float, ...], float, float]]] = {}

    def back_tracks(self, points: np.ndarray, template: int, depth: int, reach: float, link_radius: float,
                    ) -> np.ndarray:
        """``(P, depth, 3)``: the track of each of ``points`` (``(P, 3)``, frame ``template``) in
        each of the ``depth`` frames before it (the nearest first), NaN from where it breaks.

        The first step back links to the nearest point within ``reach`` (no velocity yet); each
        later one to the nearest within ``link_radius`` of where the track's last step puts it;
        either only where no other point is within ``link_radius`` more. Where two points could
        continue a track, following either may jump to another marker's track (fast gloves 30 mm
        apart), and the test would then bar a marker from its own point.
        """
        self._links = {frame: links for frame, links in self._links.items() if frame >= template - depth}
        track = np.full((len(points), depth, 3), np.nan)
        followed: list[tuple[int, int, tuple[float, ...]]] = []  # (row, frames back - 1, point)
        waiting: dict[int, list[_Walk]] = {}  # walks stopped at a link not measured yet, by their step
        empty = bisect_left(self._empty, template)  # the empty frames before the template: the last one stops all
        steps = min(depth, template - 1 - self._empty[empty - 1]) if empty else depth

        def walk(row: int, k: int, last: tuple[float, ...], step: tuple[float, ...]) -> None:
            """Follow one track back from its k-th step while the links are known."""
            while k < steps:
                at = (last[0] + step[0], last[1] + step[1], last[2] + step[2])  # as numpy adds them: the same floats
                try:
                    point, first, second = self._links[template - 1 - k][at]
                except KeyError:  # not measured yet
                    waiting.setdefault(k, []).append((row, k, last, step))
                    return
                if not (first <= (reach if k == 0 else link_radius) and second > first + link_radius):
                    return
                followed.append((row, k, point))
                k, last, step = k + 1, point, (point[0] - last[0], point[1] - last[1], point[2] - last[2])

        for row, at in enumerate(np.asarray(points, float).reshape(-1, 3).tolist()):
            walk(row, 0, tuple(at), (0.0, 0.0, 0.0))  # no velocity yet: the first step is predicted where the track is
        while waiting:  # the links of the stopped walks' next step, one frame at a time, then on
            k = min(waiting)
            stopped = waiting.pop(k)
            self._measure(template - 1 - k, [(x + dx, y + dy, z + dz) for _, _, (x, y, z), (dx, dy, dz) in stopped])
            for stop in stopped:
                walk(*stop)
        if followed:
            rows, back, points_on = zip(*followed)
            track[list(rows), list(back)] = points_on
        return track

    def _measure(self, frame: int, predicted: list[tuple[float, ...]]) -> None:
        """Keep, per predicted position, the nearest point of ``frame`` and the two smallest distances."""
        at = list(dict.fromkeys(predicted))
        points = self.frames[frame]
        nearest, first, second = _two_nearest(cdist(np.array(at), points))
        found = zip(map(tuple, points[nearest].tolist()), first.tolist(), second.tolist())
        self._links.setdefault(frame, {}).update(zip(at, found))


_Walk = tuple[int, int, tuple[float, ...], tuple[float, ...]]  # (row, steps taken, where it is, its last step back)


def _two_nearest(distance: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per row of ``distance`` (tracks x points, at least one point), the nearest point and the
    two smallest distances (inf for a second one when there is one point)."""
    nearest = distance.argmin(axis=1)
    two = np.partition(distance, 1, axis=1)[:, :2] if distance.shape[1] > 1 else np.c_[distance, np.full(len(distance), np.inf)]
    return nearest, two[:, 0], two[:, 1]


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
