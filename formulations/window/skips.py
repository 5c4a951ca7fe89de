"""Skip arcs: re-entry priced from the path's own last observation, not the template.

Jiang's network prices a box after an occlusion by the template term g(s_n, j) alone: the
occlusion node of frame m is one node for every path, so it cannot know which box the path
last took. A skip arc does: it joins observation i at frame m straight to observation j at
frame m + k (k >= 2), and costs the k - 1 misses it skips plus the re-entry priced from i,

    c(i, j) = (k - 1)(c_a + c_b) + c_a + s(i, j),

s supplied by the candidate generator (``SkipPricing``; for boxes the k-frame residual off
the object's velocity from box i, with the spread of k frames). An object seen in the
window thus pays its jump back once, against its own last box.

The network stays layered (one node per object and frame on every path, arcs between
consecutive frames only) by drawing each skip arc as a chain of *gap nodes* g(i, m+1), ...,
g(i, m+k-1), one per skipped frame, that remember i: i -> g(i, m+1) -> ... -> g(i, m+k-1)
-> j. Only i enters g(i, m+1), so the flows on the chains of i are exactly the flows on its
skip arcs (and on its arcs to the sink, the chain's end), and the LP over this network is
the LP over the skip arcs; every formulation, the rounding and the certificate read it
unchanged. The plain occlusion node of a frame (last in its block) then means "unseen
since the template": only the source and the previous plain occlusion node enter it, and
it re-enters by the template term as before. Gap nodes are OCCLUSION nodes placed before
it: they consume no resource, as occlusion nodes never do, so a skip arc belongs to no
conflict set in the frames it skips (an unseen object takes no box there), exactly as the
occlusion nodes it replaces.

A skip the pricing returns as inf is not an arc (outside the generator's gate from i).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from formulations.window.problem import OBSERVATION, OCCLUSION, SINK, SOURCE

SkipPricing = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``s(tail candidates, head candidates)`` for pairs of one object, head at least two frames
after tail: the re-entry term in the units of g(s_n, j) (inf: no arc)."""


@dataclass(frozen=True)
class GapNodes:
    """The gap nodes of every candidate: one per frame after it, to the window's end.

    Attributes:
        anchor: ``(K,)`` candidate each gap node remembers.
        object: ``(K,)`` its object.
        frame: ``(K,)`` its frame, after the anchor's.
    """

    anchor: np.ndarray
    object: np.ndarray
    frame: np.ndarray

    @classmethod
    def of(cls, candidate_object: np.ndarray, candidate_frame: np.ndarray, n_frames: int) -> GapNodes:
        after = n_frames - candidate_frame  # frames left after each candidate
        anchor = np.repeat(np.arange(len(candidate_frame)), after)
        step = np.arange(after.sum()) - np.repeat(np.cumsum(after) - after, after) + 1
        return cls(anchor, candidate_object[anchor], candidate_frame[anchor] + step)


def allowed_arcs(tail: np.ndarray, head: np.ndarray, kind: np.ndarray, anchor: np.ndarray) -> np.ndarray:
    """Which of the fully connected layer arcs the skip network keeps.

    Args:
        tail, head: ``(A,)`` arcs between consecutive frames of one object.
        kind: ``(V,)`` node kinds.
        anchor: ``(V,)`` the candidate an observation is, or a gap node remembers; -1 for
            sources, plain occlusion nodes and sinks.

    A gap node is entered only from its anchor or its own previous gap node; a plain
    occlusion node only from the source or the previous plain occlusion node; observations
    and sinks from every node.
    """
    head_kind = kind[head]
    into_gap = (head_kind == OCCLUSION) & (anchor[head] >= 0)
    into_plain = (head_kind == OCCLUSION) & (anchor[head] < 0)
    keep = (head_kind == OBSERVATION) | (head_kind == SINK)
    keep |= into_gap & (anchor[tail] == anchor[head])
    keep |= into_plain & ((kind[tail] == SOURCE) | ((kind[tail] == OCCLUSION) & (anchor[tail] < 0)))
    result: np.ndarray = keep
    return result


def skip_reentry(
    pricing: SkipPricing, reappear: float, tail: np.ndarray, head: np.ndarray, kind: np.ndarray, anchor: np.ndarray,
    candidate_of: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The arcs from a gap node into an observation, and their cost c_a + s(anchor, head).

    Their chain's earlier arcs already cost c_a + c_b per skipped frame (they enter gap
    nodes, which ``costs`` prices as occlusion), so the whole skip pays the module doc's c(i, j).
    """
    arcs = np.flatnonzero((kind[tail] == OCCLUSION) & (anchor[tail] >= 0) & (kind[head] == OBSERVATION))
    cost: np.ndarray = reappear + pricing(anchor[tail[arcs]], candidate_of[head[arcs]])
    return arcs, cost
