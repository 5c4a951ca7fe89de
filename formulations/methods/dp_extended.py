"""``dp-extended``: exact joint Viterbi over all objects at once (Jiang Sec. I, ref. [1]).

A joint state of frame m is one node per object, s = (v_1, ..., v_N), with v_n in the
(n, m) block; states using a conflict group twice are excluded. The objective splits
into terms between consecutive frames,

    E = sum_{m=0}^{M} T_m(s_m, s_{m+1}),
    T_m(s, s') = sum_n c(s_n, s'_n) + [1 <= m < M] sum_{(a, b)} mu_ab ||(r_{s'_a} - r_{s'_b}) - (r_{s_a} - r_{s_b})||_1,

with s_0 the sources and s_{M+1} the sinks, so the layout term fits the trellis exactly
and the Viterbi recursion D_{m+1}(s') = min_s D_m(s) + T_m(s, s') gives the optimum.
With k nodes per object and frame this costs O(M k^{2N}): exponential in N, which is
why Jiang's LP exists. T_m is (S_m x S_{m+1}); it is built in row chunks of next states
so memory stays bounded while every operation is a contiguous numpy gather or reduce.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from formulations.errors import FormulationError
from formulations.methods.formulation import check_parameters
from formulations.relaxation.decomposition import ComponentwiseFormulation
from formulations.window.objective import path_cost
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution

CHUNK_ELEMENTS = 1 << 20  # transition entries per chunk: 8 MB of float64, cache-sized


@dataclass(frozen=True)
class DpExtended(ComponentwiseFormulation):
    """Exact multi-object Viterbi on the joint trellis (extended DP), layout term included.

    Attributes:
        max_states: Largest joint state space of one frame (the product of the objects'
            node counts there) it will take; beyond it the window is refused with a
            FormulationError before anything is allocated.
        decompose: Solve independent components apart (Viterbi where exact), so only
            coupled components pay the joint cost.
    """

    name: ClassVar[str] = "dp-extended"
    max_states: int = 2_000_000
    decompose: bool = True

    def __post_init__(self) -> None:
        check_parameters(self, positive=("max_states",), flags=("decompose",))
        if not isinstance(self.max_states, numbers.Integral):
            raise FormulationError(f"{self.name}: parameter 'max_states' must be an integer, got {self.max_states!r}")

    def solve_coupled(self, problem: WindowProblem) -> WindowSolution:
        """Joint Viterbi over the whole (sub-)window."""
        start = time.perf_counter()
        first, sizes = problem.blocks()
        # Python ints: k^N overflows int64 long before it stops being worth reporting.
        counts = [math.prod(sizes[:, f].tolist()) for f in range(1, problem.n_frames + 1)]
        if max(counts, default=0) > self.max_states:
            worst = int(np.argmax(counts))
            raise FormulationError(
                f"{self.name}: joint state space of {counts[worst]:,} states in frame {worst + 1} "
                f"exceeds max_states = {self.max_states:,}"
            )
        groups = problem.conflict_groups.T.tocsr()  # (V, G)
        states = [_joint_states(first[:, f], sizes[:, f], groups) for f in range(problem.n_frames + 2)]
        # Arcs only join consecutive blocks of one object, so a (tail, position of head in
        # its block) table holds every arc cost densely; inf where there is no arc.
        local = np.arange(problem.n_nodes) - np.repeat(first.ravel(), sizes.ravel())
        arc_table = np.full((problem.n_nodes, sizes.max()), np.inf)
        arc_table[problem.arc_tail, local[problem.arc_head]] = problem.arc_cost
        build = time.perf_counter() - start
        distance = np.zeros(1)  # the single source state
        back = []
        for f in range(problem.n_frames + 1):
            arc_rows = [arc_table[states[f][:, n], : sizes[n, f + 1]].T.copy() for n in range(problem.n_objects)]
            distance, pointer = _advance(
                problem, distance, arc_rows, states[f], states[f + 1], local[states[f + 1]],
                layout=1 <= f < problem.n_frames,
            )
            back.append(pointer)
        solve = time.perf_counter() - start - build
        state = 0  # the single sink state
        path = np.empty((problem.n_objects, problem.n_frames), dtype=int)
        for f in range(problem.n_frames, 0, -1):
            state = back[f][state]
            path[:, f - 1] = states[f][state]
        cost = path_cost(problem, path)
        return WindowSolution(
            path=path, cost=cost, lower_bound=cost, integral=True, n_variables=sum(len(s) for s in states[1:-1]),
            build_seconds=build, solve_seconds=solve, round_seconds=time.perf_counter() - start - build - solve,
        )


def _joint_states(first: np.ndarray, sizes: np.ndarray, groups: sp.csr_matrix) -> np.ndarray:
    """``(S, N)`` node tuples of one frame that use no conflict group twice."""
    local = np.stack(np.unravel_index(np.arange(math.prod(sizes.tolist())), tuple(sizes)), axis=1)
    nodes = local + first
    s, n = nodes.shape
    chosen = sp.csr_matrix((np.ones(s * n), nodes.ravel(), np.arange(0, s * n + 1, n)), shape=(s, groups.shape[0]))
    usage = (chosen @ groups).tocoo()  # (S, G): how many of the state's nodes each group holds
    clash = np.zeros(s, dtype=bool)
    clash[usage.row[usage.data > 1]] = True
    states: np.ndarray = nodes[~clash]
    return states


def _advance(
    problem: WindowProblem, distance: np.ndarray, arc_rows: list[np.ndarray], prev: np.ndarray,
    nxt: np.ndarray, next_local: np.ndarray, layout: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """One Viterbi step: D'(s') = min_s D(s) + T(s, s'), with the arg min s of each s'.

    Arc costs come per object as ``arc_rows[n] = C_n[a_n(prev)]^T``, shape (K'_n, S): the
    row of T^T for a next state s' is then sum_n arc_rows[n][b_n(s')], so T^T is built
    from contiguous row copies and reduced along contiguous rows.

    Args:
        problem: The window.
        distance: ``(S,)`` D of the previous states ``prev`` (``(S, N)`` nodes).
        arc_rows: Per object, the arc costs from each previous state to its next nodes.
        nxt: ``(S', N)`` next states (nodes).
        next_local: The same next states as node positions within their blocks.
        layout: Whether the layout term joins these two frames (both in 1..M).
    """
    pairs = np.flatnonzero(problem.layout_weight > 0) if layout else np.zeros(0, int)
    location = problem.node_location
    relative = [location[prev[:, a]] - location[prev[:, b]] for a, b in problem.layout_pairs[pairs]]
    best, pointer = np.empty(len(nxt)), np.empty(len(nxt), dtype=np.int64)
    step = max(1, CHUNK_ELEMENTS // len(prev))
    scratch = np.empty((min(step, len(nxt)), len(prev)))
    for lo in range(0, len(nxt), step):
        hi = min(lo + step, len(nxt))
        total = np.take(arc_rows[0], next_local[lo:hi, 0], axis=0)
        for n in range(1, problem.n_objects):
            total += np.take(arc_rows[n], next_local[lo:hi, n], axis=0, out=scratch[: hi - lo])
        total += distance
        for (a, b), weight, rel in zip(problem.layout_pairs[pairs], problem.layout_weight[pairs], relative):
            rel_next = location[nxt[lo:hi, a]] - location[nxt[lo:hi, b]]
            total += weight * cdist(rel_next, rel, metric="cityblock")
        pointer[lo:hi] = np.argmin(total, axis=1)
        best[lo:hi] = total[np.arange(hi - lo), pointer[lo:hi]]
    return best, pointer
