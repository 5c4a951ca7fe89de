"""Build the window network (nodes, fully connected layers, arc costs) from candidates."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights, arc_costs
from formulations.window.likelihood import likelihood_arc_costs
from formulations.window.problem import OBSERVATION, OCCLUSION, SINK, SOURCE, WindowProblem


def build_window(
    candidates: WindowCandidates,
    weights: ArcCostWeights = ArcCostWeights(),
    layout_pairs: np.ndarray | None = None,
    layout_weight: np.ndarray | float = 0.0,
) -> tuple[WindowProblem, np.ndarray]:
    """Pose one window as a WindowProblem.

    Args:
        candidates: Candidate observations of the window.
        weights: Arc cost weights.
        layout_pairs: ``(P, 2)`` object pairs under the layout term (None: no pairs).
        layout_weight: mu, one value or one per pair.

    Returns:
        The problem, and for every node the index of its candidate (-1 for source,
        occlusion and sink nodes): what the caller needs to map a solution back.
    """
    n, m, c = candidates.n_objects, candidates.n_frames, len(candidates.object)
    objects = np.arange(n)
    obj_frames = (np.repeat(objects, m), np.tile(np.arange(1, m + 1), n))
    node_object = np.concatenate([objects, candidates.object, obj_frames[0], objects])
    node_frame = np.concatenate([np.zeros(n, int), candidates.frame, obj_frames[1], np.full(n, m + 1)])
    node_kind = np.concatenate(
        [np.full(n, SOURCE), np.full(c, OBSERVATION), np.full(n * m, OCCLUSION), np.full(n, SINK)]
    )
    # Occlusion last in its frame: the paper's "largest state number".
    order = np.lexsort((node_kind == OCCLUSION, node_frame, node_object))
    node_object, node_frame, node_kind = node_object[order], node_frame[order], node_kind[order]

    dim = candidates.location.shape[1]
    location = np.concatenate(
        [candidates.template_location, candidates.location,
         candidates.occlusion_location.reshape(n * m, dim), np.zeros((n, dim))]
    )[order]
    source_of = np.concatenate([np.arange(n), np.full(c + n * m + n, -1)])[order]
    candidate_of = np.concatenate([np.full(n, -1), np.arange(c), np.full(n * m + n, -1)])[order]
    template_cost = np.zeros(len(order))
    is_candidate = candidate_of >= 0
    template_cost[is_candidate] = candidates.template_cost[candidate_of[is_candidate]]

    tail, head, block_pairs = _layer_arcs(node_object, node_frame)
    motion = np.zeros_like(location)
    inner = (node_frame >= 1) & (node_frame <= m)
    motion[inner] = candidates.motion[node_object[inner], node_frame[inner] - 1]
    source_occluded = np.zeros(len(order), dtype=bool)
    source_occluded[source_of >= 0] = candidates.template_occluded[source_of[source_of >= 0]]
    if candidates.likelihood is None:
        cost = arc_costs(
            weights, tail, head, node_kind, location, template_cost, motion,
            _appearance_change(_node_appearance(candidates, order), block_pairs), source_occluded,
        )
    else:
        cost = likelihood_arc_costs(
            weights.template_on_track, _node_likelihood(candidates, candidate_of, node_object, node_frame, node_kind),
            tail, head, node_kind, location, template_cost, motion, source_occluded,
        )
    problem = WindowProblem(
        n_objects=n, n_frames=m, node_kind=node_kind, node_object=node_object,
        node_frame=node_frame, node_location=location,
        resources=_node_resources(candidates.resources, candidate_of),
        arc_tail=tail, arc_head=head, arc_cost=cost,
        **_layout(layout_pairs, layout_weight, n),
    )
    return problem, candidate_of


def taken_candidates(node_candidate: np.ndarray, path: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``index[c]`` of the candidate c on each path node, -1 at source, occlusion and sink nodes.

    Args:
        node_candidate: Candidate of each node (``build_window``), -1 for the others.
        path: Node per object and frame (``WindowSolution.path``).
        index: Per candidate, what it stands for (a point or detection index).

    A window may have no candidate at all (every frame after its template empty: the
    subject left the volume); every path then runs through occlusion nodes and ``index``
    is empty. The -1 appended to ``index`` is what ``node_candidate == -1`` selects, so
    no candidate is ever looked up that does not exist.
    """
    taken: np.ndarray = np.append(index, -1)[node_candidate[path]]
    return taken


def _layer_arcs(node_object: np.ndarray, node_frame: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All arcs from each (object, frame) block to the next block of the same object.

    A block pair with a tails and b heads gives a*b arcs, tail-major; built with
    repeat/arange so there is no Python loop over arcs or blocks.

    Returns:
        Arc tails, arc heads, and per block pair (first tail, a, first head, b).
    """
    starts = np.flatnonzero(np.r_[True, (node_object[1:] != node_object[:-1]) | (node_frame[1:] != node_frame[:-1])])
    sizes = np.diff(np.r_[starts, len(node_object)])
    linked = np.flatnonzero(node_object[starts[:-1]] == node_object[starts[1:]])
    a, b = sizes[linked], sizes[linked + 1]
    counts = a * b
    offset = np.repeat(np.cumsum(counts) - counts, counts)
    local = np.arange(counts.sum()) - offset
    b_rep = np.repeat(b, counts)
    tail = np.repeat(starts[linked], counts) + local // b_rep
    head = np.repeat(starts[linked + 1], counts) + local % b_rep
    return tail, head, np.column_stack([starts[linked], a, starts[linked + 1], b])


def _node_likelihood(
    candidates: WindowCandidates, candidate_of: np.ndarray, node_object: np.ndarray, node_frame: np.ndarray,
    node_kind: np.ndarray,
) -> dict[str, np.ndarray]:
    """The candidates' likelihood terms spread over nodes (zero where a term does not apply)."""
    assert candidates.likelihood is not None
    like, v = candidates.likelihood, len(candidate_of)
    is_candidate = candidate_of >= 0
    spread = {}
    for name in ("step_sigma", "step_offset", "reappear_cost"):
        values = np.ones(v) if name == "step_sigma" else np.zeros(v)
        values[is_candidate] = getattr(like, name)[candidate_of[is_candidate]]
        spread[name] = values
    miss = np.zeros(v)
    occlusion = node_kind == OCCLUSION
    miss[occlusion] = like.miss_cost[node_object[occlusion], node_frame[occlusion] - 1]
    spread["miss_cost"] = miss
    return spread


def _appearance_change(appearance: np.ndarray | None, block_pairs: np.ndarray) -> np.ndarray | None:
    """g(i, j) = half the L1 distance of the histograms, for every arc in arc order.

    One cdist per block pair (a loop over blocks, not arcs): indexing the histograms of
    every arc instead would copy arcs x bins values twice.
    """
    if appearance is None:
        return None
    blocks = [
        cdist(appearance[t : t + a], appearance[h : h + b], metric="cityblock").ravel()
        for t, a, h, b in block_pairs
    ]
    return 0.5 * np.concatenate(blocks) if blocks else np.zeros(0)


def _node_appearance(candidates: WindowCandidates, order: np.ndarray) -> np.ndarray | None:
    if candidates.appearance is None or candidates.template_appearance is None:
        return None
    n, m = candidates.n_objects, candidates.n_frames
    h = candidates.appearance.shape[1]
    filler = np.zeros((n * m + n, h))
    stacked = np.concatenate([candidates.template_appearance, candidates.appearance, filler])
    node_appearance: np.ndarray = stacked[order]
    return node_appearance


def _node_resources(resources: sp.csr_matrix, candidate_of: np.ndarray) -> sp.csr_matrix:
    """Resource rows per node; non-candidate nodes consume nothing."""
    rows = np.flatnonzero(candidate_of >= 0)
    selector = sp.csr_matrix(
        (np.ones(len(rows)), (rows, candidate_of[rows])), shape=(len(candidate_of), resources.shape[0])
    )
    return (selector @ sp.csr_matrix(resources)).tocsr()


def _layout(pairs: np.ndarray | None, weight: np.ndarray | float, n: int) -> dict[str, np.ndarray]:
    pairs = np.zeros((0, 2), dtype=int) if pairs is None else np.asarray(pairs, dtype=int).reshape(-1, 2)
    weights = np.broadcast_to(np.asarray(weight, dtype=float), (len(pairs),)).copy()
    if len(pairs) and (pairs.min() < 0 or pairs.max() >= n or (pairs[:, 0] == pairs[:, 1]).any()):
        raise ValueError("layout pairs must join two different objects of the window")
    if (weights < 0).any() or not np.isfinite(weights).all():
        raise ValueError("layout weight mu must be finite and >= 0")
    return {"layout_pairs": pairs, "layout_weight": weights}
