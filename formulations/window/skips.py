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
the LP over the skip arcs; every formulation and the certificate read it unchanged (the
greedy rounding of a fractional optimum reconnects its choices, ``relaxation.rounding``).
The plain occlusion node of a frame (last in its block) then means "unseen since the
template": only the source and the previous plain occlusion node enter it, and it
re-enters by the template term as before. Gap nodes are OCCLUSION nodes placed before it:
they consume no resource, as occlusion nodes never do, so a skip arc belongs to no conflict
set in the frames it skips (an unseen object takes no box there), exactly as the occlusion
nodes it replaces.

Returned steps (``returned_steps``, on top): once a path has re-entered (after a gap, or
unseen at the template), the template's forecast no longer says where its next box is; its
own last box does. Every observation gets a *returned copy*, entered only from returned
nodes (an occluded source, gap and plain occlusion nodes, returned copies), and a step
between returned copies pays t s(i, j) (k = 1) in place of t g(s_n, j); the original
("tracked") copies are entered only from a seen source and tracked copies, and cost as in
Jiang's network. The two copies of a box hold the same resources, so they are one box to
every conflict set. A lost object that takes a chain then pays its jump once (the template
term on the first box) and each later box against the box before it.

A skip the pricing returns as inf is not an arc (outside the generator's gate from i); nor
is a returned step it prices inf.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from formulations.window.problem import OBSERVATION, OCCLUSION, SINK, SOURCE

SkipPricing = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``s(tail candidates, head candidates)`` for pairs of one object, head at least one frame
after tail: the re-entry term in the units of g(s_n, j) (inf: no arc)."""


@dataclass(frozen=True)
class PathNodes:
    """The nodes the skip network adds to Jiang's: gap nodes, and with ``returned_steps`` a
    returned copy of every candidate (module doc).

    Attributes:
        candidate: ``(K,)`` the candidate a returned copy is, -1 for gap nodes.
        anchor: ``(K,)`` the candidate a gap node remembers, and a returned copy is.
        object: ``(K,)`` object of each node.
        frame: ``(K,)`` frame of each node.
    """

    candidate: np.ndarray
    anchor: np.ndarray
    object: np.ndarray
    frame: np.ndarray

    @classmethod
    def of(cls, candidate_object: np.ndarray, candidate_frame: np.ndarray, n_frames: int,
           returned_steps: bool) -> PathNodes:
        after = n_frames - candidate_frame  # frames left after each candidate: one gap node each
        gap_anchor = np.repeat(np.arange(len(candidate_frame)), after)
        step = np.arange(after.sum()) - np.repeat(np.cumsum(after) - after, after) + 1
        copies = np.arange(len(candidate_frame)) if returned_steps else np.zeros(0, int)
        anchor = np.r_[copies, gap_anchor]
        frame = np.r_[candidate_frame[copies], candidate_frame[gap_anchor] + step]
        return cls(np.r_[copies, np.full(len(gap_anchor), -1)], anchor, candidate_object[anchor], frame)


def allowed_arcs(tail: np.ndarray, head: np.ndarray, kind: np.ndarray, anchor: np.ndarray,
                 returned: np.ndarray | None) -> np.ndarray:
    """Which of the fully connected layer arcs the skip network keeps.

    Args:
        tail, head: ``(A,)`` arcs between consecutive frames of one object.
        kind: ``(V,)`` node kinds.
        anchor: ``(V,)`` the candidate an observation is, or a gap node remembers; -1 for
            sources, plain occlusion nodes and sinks.
        returned: ``(V,)`` True where the path has been unseen since the template or after
            one of its boxes (occluded sources, gap and plain occlusion nodes, returned
            copies), or None without returned copies.

    A gap node is entered only from its anchor or its own previous gap node; a plain
    occlusion node only from the source or the previous plain occlusion node; sinks from
    every node; observations from every node, or, with returned copies, a returned copy
    only from a returned node and a tracked one only from a tracked one.
    """
    head_kind = kind[head]
    gap = (kind == OCCLUSION) & (anchor >= 0)
    plain = (kind == OCCLUSION) & (anchor < 0)
    into_observation = head_kind == OBSERVATION
    if returned is not None:
        into_observation &= returned[tail] == returned[head]
    keep = into_observation | (head_kind == SINK)
    keep |= gap[head] & (anchor[tail] == anchor[head])
    keep |= plain[head] & ((kind[tail] == SOURCE) | plain[tail])
    result: np.ndarray = keep
    return result


def path_costs(
    pricing: SkipPricing, reappear: float, template_on_track: float, tail: np.ndarray, head: np.ndarray,
    kind: np.ndarray, anchor: np.ndarray, returned: np.ndarray | None, template_cost: np.ndarray, cost: np.ndarray,
) -> np.ndarray:
    """``cost`` (Jiang's, per arc) with the re-entries and returned steps priced from the path's own box.

    An arc from a gap node into an observation costs c_a + s(anchor, head): the chain's
    earlier arcs already cost c_a + c_b per skipped frame (they enter gap nodes, which
    ``costs`` prices as occlusion), so the whole skip pays the module doc's c(i, j). A step
    between returned copies pays t s(tail, head) in place of t g(s_n, head).
    """
    priced = cost.copy()
    gap_tail = (kind[tail] == OCCLUSION) & (anchor[tail] >= 0)
    arcs = np.flatnonzero(gap_tail & (kind[head] == OBSERVATION))
    priced[arcs] = reappear + pricing(anchor[tail[arcs]], anchor[head[arcs]])
    if returned is not None:
        steps = np.flatnonzero((kind[tail] == OBSERVATION) & (kind[head] == OBSERVATION) & returned[head])
        own = pricing(anchor[tail[steps]], anchor[head[steps]])
        priced[steps] += template_on_track * (own - template_cost[head[steps]])
    return priced
