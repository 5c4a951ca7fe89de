"""``mht``: Ringer & Lasenby's multiple hypothesis tracker (2002, Sec. 2) over one window.

A hypothesis is one node per object at frame m with the cost of its path so far (eq. 13 in
cost form, -log P^Psi up to a constant: the costs of its steps add). For m = 1..M, each of
the I hypotheses kept is expanded by its J best associations of frame m: the assignment
problem F of ``mht_association`` (eq. 10: objects x contested resources, private
columns, occlusion as the miss) ranked by Murty's algorithm (``formulations.assignment``;
the hypotheses of a frame differ in a few markers, so their F share most blocks, and one
``RankingCache`` per frame ranks each distinct block once). A child's step costs

    F(sigma) + [m >= 2] sum_{(a, b)} mu_ab ||(r_a,m - r_b,m) - (r_a,m-1 - r_b,m-1)||_1,

its association plus the layout term between its two frames (pairwise, so it cannot sit
in F: it re-scores the J associations, as eq. 13 re-scores with the re-estimated state).
Children with the same frame-m nodes merge (the cheaper stays, as in the paper), and the
I cheapest go on. At the sinks the cheapest path is the window's answer. The contract's
cost, ``path_cost``, is reported for it.

The state. The window's arc costs already hold each object's predicted motion, so with
``noise`` None the state is held fixed at the one the window was posed with, and the
search ranks exactly E. With ``noise`` sigma each hypothesis re-estimates a constant
velocity per marker from its own last two nodes, and F gains the term
||r_v - (2 r_prev - r_prev2)||^2 / (2 sigma^2) for observations v (from m = 2: the source
is r_prev2). Rigid segments enter as the layout pairs, the only segments a window knows;
the subject model itself is not in a ``WindowProblem``.

lambda_FA and lambda_D of eq. 8 are not parameters here: within the contract a point no
object takes costs nothing and there is no image area A for p_FA = 1/A, so a false-alarm
price would only shift every observation's cost against the occlusion arcs, which
already carry the miss price (the window's ``reappear``/``disappear`` weights, -log(1 -
P_D) in the paper's terms). They are set where the window is posed, and so is the
occlusion-aware P_D of eq. 8 (``formulations.cameras.visibility``): a chain that prices a
marker's arcs in camera c by -log P_D and -log(1 - P_D) hands ``mht`` the paper's F
(tests/test_mht_figure.py poses the paper's Figs 3-5 that way).

Bound: -inf, unless the search was exhaustive: every hypothesis's associations all
ranked (fewer than J + 1 exist), no hypothesis dropped by the I cut, ``noise`` None and
every conflict group within one frame. Then merging is exact (the future of a hypothesis
depends on its frame-m nodes only) and the search is Viterbi over every joint state, as
``dp-extended``: the answer is optimal and reported with lower_bound = cost.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from formulations.assignment.blocks import k_best_assignments
from formulations.assignment.rankings import RankingCache
from formulations.methods.formulation import MAX_BRANCHING, TABLE_BRANCHING, Formulation, check_parameters
from formulations.methods.frame_steps import FrameSteps
from formulations.methods.mht_association import Association, association
from formulations.window.objective import path_cost
from formulations.window.problem import OBSERVATION, WindowProblem
from formulations.window.solution import WindowSolution

FILTER_ROUNDS = 6  # doublings of k when infeasible assignments are filtered out


@dataclass(frozen=True)
class Mht(Formulation):
    """Multiple hypothesis tracking (Ringer & Lasenby): I hypotheses, J associations each by Murty.

    Attributes:
        hypotheses: I, hypotheses kept after each frame (the cheapest, merged), 1 to 100 (code: 10^4).
        associations: J, best associations (Murty's k-best) expanding each hypothesis, 1 to 100 (code: 10^4).
        noise: sigma of the constant-velocity prediction's error per hypothesis (sensor
            noise and the marker's acceleration together), in location units; None holds
            the state fixed (the arc costs alone rank). Not the sensor's noise: at 1 mm
            every acceleration of a walk costs more than a miss, and markers are dropped
            (1 mm scenarios: 85_02 73.3 % right against 99.87 % with None, the gait2354
            walk 49 % against 100 %).
    """

    name: ClassVar[str] = "mht"
    table_limits: ClassVar[dict[str, float]] = {"hypotheses": TABLE_BRANCHING, "associations": TABLE_BRANCHING}
    hypotheses: int = 5
    associations: int = 5
    noise: float | None = None

    def __post_init__(self) -> None:
        check_parameters(self, positive=("hypotheses", "associations"), optional_positive=("noise",),
                         integers=("hypotheses", "associations"),
                         at_most={"hypotheses": MAX_BRANCHING, "associations": MAX_BRANCHING})

    def solve(self, problem: WindowProblem) -> WindowSolution:
        start = time.perf_counter()
        steps = FrameSteps(problem)
        sources = problem.source_nodes()
        nodes = sources[None, :]  # (H, N): each hypothesis's nodes at the current frame
        before = sources[None, :]  # their nodes one frame earlier (velocity)
        score, taken = np.zeros(1), np.zeros((1, steps.node_groups.shape[1]))
        parents: list[NDArray[np.intp]] = []
        layers: list[NDArray[np.intp]] = []
        exhaustive = self.noise is None and _groups_within_frames(problem)
        for m in range(problem.n_frames):
            children, parent, child_score, complete = self._expand(
                problem, steps, nodes, before, taken, score, m, probe=exhaustive,
            )
            exhaustive &= complete and len(children) <= self.hypotheses
            keep = _merge_and_cut(children, child_score, self.hypotheses)
            before, nodes, score = nodes[parent[keep]], children[keep], child_score[keep]
            taken = taken[parent[keep]]
            holder, group = steps.node_groups[nodes.ravel()].nonzero()  # every hypothesis at once
            taken[holder // nodes.shape[1], group] = 1.0
            parents.append(parent[keep])
            layers.append(nodes)
        sink_cost = np.array([steps.successors(nodes[h], taken[h])[1].sum() for h in range(len(nodes))])
        best = int(np.argmin(score + sink_cost))
        path = np.empty((problem.n_objects, problem.n_frames), dtype=int)
        for m in range(problem.n_frames - 1, -1, -1):
            path[:, m] = layers[m][best]
            best = int(parents[m][best])
        cost = path_cost(problem, path)
        return WindowSolution(
            path=path, cost=cost, lower_bound=cost if exhaustive else -np.inf, integral=exhaustive,
            status="Optimal" if exhaustive else "heuristic", solve_seconds=time.perf_counter() - start,
        )

    def _expand(
        self, problem: WindowProblem, steps: FrameSteps, nodes: NDArray[np.intp], before: NDArray[np.intp],
        taken: NDArray[np.float64], score: NDArray[np.float64], m: int, probe: bool,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64], bool]:
        """Every hypothesis's J best children at frame m + 1: nodes, parent, score, and
        whether each hypothesis's associations were all ranked (known only if ``probe``)."""
        children: list[NDArray[np.intp]] = []
        parent: list[int] = []
        child_score: list[float] = []
        complete = True
        cache = RankingCache()  # the hypotheses differ in a few markers: most blocks of F recur
        for h in range(len(nodes)):
            node, cost, held = steps.successors(nodes[h], taken[h])
            if self.noise is not None and m >= 1:
                cost = cost + _velocity_cost(problem, node, nodes[h], before[h], self.noise)
            f = association(problem.n_objects, problem.node_object, problem.node_kind, node, cost, held)
            probe &= complete and len(children) <= self.hypotheses  # else the search is cut already
            ranked, exhausted = _feasible_best(f, steps, self.associations, probe, cache)
            complete &= exhausted
            for step_cost, chosen in ranked:
                layout = _layout_step(problem, nodes[h], chosen) if m >= 1 else 0.0
                children.append(chosen)
                parent.append(h)
                child_score.append(score[h] + step_cost + layout)
        return np.array(children), np.array(parent), np.array(child_score), complete


def _feasible_best(
    f: Association, steps: FrameSteps, j: int, probe: bool, cache: RankingCache,
) -> tuple[list[tuple[float, NDArray[np.intp]]], bool]:
    """The J best associations holding no resource twice, as (cost, nodes); and whether
    they are all there are (with ``probe`` J + 1 are asked, so a cut list is seen as cut;
    without, a full list counts as cut)."""
    k = j + probe
    for _ in range(FILTER_ROUNDS):
        ranked = k_best_assignments(f.cost, f.miss, k, cache)
        found = list(zip((a.cost for a in ranked), f.nodes(np.array([a.columns for a in ranked]).reshape(len(ranked), -1))))
        if f.checked:
            found = [(c, n) for c, n in found if (steps.node_groups[n].sum(axis=0) <= 1).all()]
        if len(ranked) < k or len(found) >= j + probe:
            return found[:j], len(ranked) < k and len(found) <= j
        k *= 2
    if not found and np.isfinite(f.miss).all():
        # every ranked assignment held a resource twice: every object occluded holds none, so a
        # hypothesis always has this child (it had none, and the search ended in an IndexError)
        found = [(float(f.miss.sum()), f.occlusion.copy())]
    return found[:j], False


def _merge_and_cut(children: NDArray[np.intp], score: NDArray[np.float64], keep: int) -> NDArray[np.intp]:
    """Indices of the ``keep`` cheapest children with distinct nodes (the cheaper of a merge)."""
    distinct: list[int] = []
    seen: set[bytes] = set()
    for child in np.argsort(score, kind="stable").tolist():
        nodes = children[child].tobytes()
        if nodes not in seen:
            seen.add(nodes)
            distinct.append(child)
            if len(distinct) == keep:
                break
    return np.array(distinct, dtype=np.intp)


def _layout_step(problem: WindowProblem, previous: NDArray[np.intp], chosen: NDArray[np.intp]) -> float:
    """sum mu_ab ||(r_a' - r_b') - (r_a - r_b)||_1 between two consecutive frames."""
    if len(problem.layout_pairs) == 0:
        return 0.0
    a, b = problem.layout_pairs[:, 0], problem.layout_pairs[:, 1]
    r, r_next = problem.node_location[previous], problem.node_location[chosen]
    change = np.abs((r_next[a] - r_next[b]) - (r[a] - r[b])).sum(axis=1)
    return float(problem.layout_weight @ change)


def _velocity_cost(
    problem: WindowProblem, node: NDArray[np.intp], previous: NDArray[np.intp], before: NDArray[np.intp], noise: float,
) -> NDArray[np.float64]:
    """||r_v - (2 r_prev - r_prev2)||^2 / (2 sigma^2) for observations v, 0 for occlusions."""
    obj = problem.node_object[node]
    location = problem.node_location
    predicted = 2 * location[previous[obj]] - location[before[obj]]
    residual = location[node] - predicted
    term: NDArray[np.float64] = np.einsum("ad,ad->a", residual, residual) / (2 * noise**2)
    return np.where(problem.node_kind[node] == OBSERVATION, term, 0.0)


def _groups_within_frames(problem: WindowProblem) -> bool:
    """Whether every conflict group's nodes lie in one frame (then merging is exact)."""
    groups = problem.conflict_groups.tocoo()
    frame = problem.node_frame[groups.col]
    low, high = np.full(groups.shape[0], np.iinfo(np.int64).max), np.full(groups.shape[0], -1)
    np.minimum.at(low, groups.row, frame)
    np.maximum.at(high, groups.row, frame)
    return bool((low == high).all()) if groups.shape[0] else True
