"""One pose hypothesis (or none) per segment, jointly over the skeleton tree: exact max-sum.

A constellation that is its own mirror image (four markers round a pelvis, three on a
thigh), or three markers that happen to match three unrelated points, fits the cloud as
well as the truth; only its joints tell them apart. So the choice is made for all segments
at once: with x_s in H_s ∪ {none} and score(h) = inliers(h) - rms(h) / (2 mean tau_s),

    max  sum_s score(x_s) + support(x_s)   subject to, for every joint (s, t) with x_s, x_t both chosen:
         |R_s c_s + d_s - (R_t c_t + d_t)| <= joint tolerance  and  no point shared.

The joints form a forest (``skeleton`` keeps no loop), so dynamic programming from the
leaves up is exact: best_s(x) = score(x) + sum_children max_{y compatible with x} best_c(y),
where ``none`` is compatible with everything (an unseen segment does not constrain).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.distance import cdist

from formulations.subject.constellation import Hypotheses, Hypothesis
from formulations.subject.geometry import ModelGeometry

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]


def choose_hypotheses(
    geometry: ModelGeometry, by_segment: Sequence[Sequence[Hypothesis]], points: int, support: list[Array] | None = None,
) -> dict[int, Hypothesis]:
    """The jointly best hypothesis of each segment that gets one.

    ``support`` (per segment, per hypothesis) is added to its score: markers of other
    segments the hypothesis explains (``chain_support``).
    """
    stacked = [_Stacked.of(h, points) for h in by_segment]
    score = [_scores(geometry, s, h) for s, h in enumerate(stacked)]
    if support is not None:
        score = [value + np.append(extra, 0.0) for value, extra in zip(score, support)]
    neighbours: dict[int, list[tuple[int, Mask]]] = {s: [] for s in range(len(by_segment))}
    for joint in geometry.joints:
        allowed = _compatible(stacked[joint.a], stacked[joint.b], joint.centre_a, joint.centre_b, joint.tolerance)
        neighbours[joint.a].append((joint.b, allowed))
        neighbours[joint.b].append((joint.a, allowed.T))
    chosen: dict[int, Hypothesis] = {}
    seen: set[int] = set()
    for root in range(len(by_segment)):
        if root in seen:
            continue
        order, parent = _tree(root, neighbours, seen)
        best = {s: score[s].copy() for s in order}
        pick: dict[int, dict[int, NDArray[np.int64]]] = {s: {} for s in order}
        for s in reversed(order):  # leaves first
            for child, allowed in neighbours[s]:
                if parent.get(child) != s:
                    continue
                value = np.where(allowed, best[child][None], -np.inf)  # (|H_s| + 1, |H_c| + 1)
                pick[s][child] = value.argmax(axis=1)
                best[s] += value.max(axis=1)
        state = {root: int(best[root].argmax())}
        for s in order:
            for child, argmax in pick[s].items():
                state[child] = int(argmax[state[s]])
        for s, x in state.items():
            if x < len(by_segment[s]):
                chosen[s] = by_segment[s][x]
    return chosen


@dataclass(frozen=True)
class _Stacked:
    """A segment's hypotheses as arrays (hundreds of them: no loop over Python objects)."""

    rotation: Array  # (H, 3, 3)
    origin: Array  # (H, 3)
    uses: NDArray[np.uint8]  # (H, ceil(points / 8)): the points each hypothesis takes, as packed bit rows
    inliers: Array  # (H,)
    rms: Array  # (H,)

    @classmethod
    def of(cls, hypotheses: Sequence[Hypothesis], points: int) -> _Stacked:
        if not hypotheses:
            return cls(np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, (points + 7) // 8), np.uint8), np.zeros(0),
                       np.zeros(0))
        if isinstance(hypotheses, Hypotheses):
            rotation, origin, taken, rms = hypotheses.rotation, hypotheses.origin, hypotheses.point, hypotheses.rms
        else:
            rotation, origin = np.stack([h.pose.rotation for h in hypotheses]), np.stack([h.pose.origin for h in hypotheses])
            taken, rms = np.stack([h.point for h in hypotheses]), np.array([h.rms for h in hypotheses])
        rows, cols = np.nonzero(taken >= 0)
        uses = np.zeros((len(hypotheses), points), bool)
        uses[rows, taken[rows, cols]] = True
        return cls(rotation, origin, np.packbits(uses, axis=1), (taken >= 0).sum(axis=1).astype(float), rms)

    def place(self, local: Array) -> Array:
        """``(H, 3)`` where each hypothesis puts the point ``local`` of the segment frame."""
        placed: Array = np.einsum("hij,j->hi", self.rotation, local) + self.origin
        return placed


def _scores(geometry: ModelGeometry, segment: int, hypotheses: _Stacked) -> Array:
    """score(h) per hypothesis, and 0 for ``none`` (the last entry)."""
    tau = float(geometry.segments[segment].tolerance.mean())
    return np.append(hypotheses.inliers - hypotheses.rms / (2 * tau), 0.0)


def _compatible(a: _Stacked, b: _Stacked, centre_a: Array, centre_b: Array, tolerance: float) -> NDArray[np.bool_]:
    """``(|H_a| + 1, |H_b| + 1)`` pairs allowed across a joint; ``none`` (last row, column) goes with all."""
    allowed = np.ones((len(a.rms) + 1, len(b.rms) + 1), bool)
    if not len(a.rms) or not len(b.rms):
        return allowed
    close = np.nonzero(cdist(a.place(centre_a), b.place(centre_b)) <= tolerance)
    # Shared points looked for only in the pairs that meet at the joint (a few in a thousand
    # on 03_rolling, whose segments have hundreds of hypotheses each).
    shared = (a.uses[close[0]] & b.uses[close[1]]).any(axis=1)
    allowed[:-1, :-1] = False
    allowed[close[0][~shared], close[1][~shared]] = True
    return allowed


def _tree(root: int, neighbours: dict[int, list[tuple[int, Mask]]], seen: set[int]) -> tuple[list[int], dict[int, int]]:
    """Breadth-first order of ``root``'s tree and each node's parent; marks the nodes seen."""
    order, parent, queue = [], {}, [root]
    seen.add(root)
    while queue:
        s = queue.pop(0)
        order.append(s)
        for t, _ in neighbours[s]:
            if t not in seen:
                seen.add(t)
                parent[t] = s
                queue.append(t)
    return order, parent
