"""Tiny random windows and an exhaustive solver for them (test helpers).

The exhaustive solver and the objective here are written from the definitions (Jiang
Sec. II-B/C) with their own arc lookup and their own conflict test, sharing no code with
``formulations.window.objective`` or the LP, so tests that compare against them can fail.
"""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from formulations.window.build import build_window
from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights
from formulations.window.likelihood import CandidateLikelihood
from formulations.window.problem import WindowProblem


def random_window(
    seed: int, n_objects: int = 3, n_frames: int = 3, n_points: int = 4, per_object: int | tuple[int, ...] = 2,
    mu: float = 0.0, dim: int = 2, likelihood: bool = False,
) -> WindowProblem:
    """Objects drawing ``per_object`` candidates each frame (or object n ``per_object[n]``) from
    ``n_points`` shared points.

    ``likelihood``: price arcs by random negative log-likelihood terms
    (``formulations.window.likelihood``) instead of Jiang's weights.
    """
    rng = np.random.default_rng(seed)
    points = rng.uniform(0, 10, size=(n_frames, n_points, dim))
    objects, frames, ids = [], [], []
    drawn = (per_object,) * n_objects if isinstance(per_object, int) else per_object
    for n in range(n_objects):
        for m in range(n_frames):
            chosen = rng.choice(n_points, size=drawn[n], replace=False)
            objects += [n] * drawn[n]
            frames += [m + 1] * drawn[n]
            ids += list(m * n_points + chosen)
    objects, frames, ids = np.array(objects), np.array(frames), np.array(ids)
    location = points.reshape(-1, dim)[ids]
    candidates = WindowCandidates(
        template_location=rng.uniform(0, 10, size=(n_objects, dim)),
        template_occluded=np.zeros(n_objects, bool), n_frames=n_frames,
        object=objects, frame=frames, location=location,
        template_cost=rng.uniform(0, 2, size=len(ids)),
        resources=sp.csr_matrix((np.ones(len(ids)), (np.arange(len(ids)), ids)), shape=(len(ids), n_frames * n_points)),
        occlusion_location=rng.uniform(0, 10, size=(n_objects, n_frames, dim)),
        motion=np.zeros((n_objects, n_frames, dim)),
        likelihood=CandidateLikelihood(
            step_sigma=rng.uniform(0.5, 3, len(ids)), step_offset=rng.uniform(0, 2, len(ids)),
            reappear_cost=rng.uniform(0, 6, len(ids)), miss_cost=rng.uniform(1, 4, (n_objects, n_frames)),
        ) if likelihood else None,
    )
    pairs = np.array(list(itertools.combinations(range(n_objects), 2))) if mu > 0 else None
    weights = ArcCostWeights(displacement=1.0, reappear=3.0, disappear=3.0)
    return build_window(candidates, weights, pairs, mu)[0]


# The shared tiny windows of the formulation contract: label -> random_window arguments.
# 2-3 objects drawing 2 of 3-4 shared points per frame, so conflicts bind and occlusion
# nodes are on optimal paths; "fractional" ones have a fractional LP optimum, so rounding
# matters. The layout windows add the L1 layout term (their LPs are fractional).
SHARED_WINDOWS: dict[str, dict] = {
    "conflicts-3x3-a": dict(seed=1, n_objects=3, n_frames=3, n_points=3, per_object=2),
    "conflicts-3x3-b": dict(seed=3, n_objects=3, n_frames=3, n_points=3, per_object=2),
    "conflicts-3x3-fractional-a": dict(seed=53, n_objects=3, n_frames=3, n_points=3, per_object=2),
    "conflicts-3x3-fractional-b": dict(seed=101, n_objects=3, n_frames=3, n_points=3, per_object=2),
    "conflicts-3x2-fractional": dict(seed=19, n_objects=3, n_frames=2, n_points=3, per_object=2),
    "conflicts-2x3": dict(seed=0, n_objects=2, n_frames=3, n_points=3, per_object=2),
    "conflicts-3x3-4-points": dict(seed=0, n_objects=3, n_frames=3, n_points=4, per_object=2),
    "layout-3x3-mu-0.3": dict(seed=5, n_objects=3, n_frames=3, n_points=3, per_object=2, mu=0.3),
    "layout-2x3-mu-0.3": dict(seed=3, n_objects=2, n_frames=3, n_points=3, per_object=2, mu=0.3),
    "layout-3x2-mu-1": dict(seed=6, n_objects=3, n_frames=2, n_points=3, per_object=2, mu=1.0),
    "layout-3x3-4-points-mu-1": dict(seed=2, n_objects=3, n_frames=3, n_points=4, per_object=2, mu=1.0),
}


def shared_window(label: str) -> WindowProblem:
    """One of the ``SHARED_WINDOWS``."""
    return random_window(**SHARED_WINDOWS[label])


def arc_table(problem: WindowProblem) -> dict[tuple[int, int], float]:
    """Cost of every arc keyed by (tail, head), by a plain loop."""
    return {(int(t), int(h)): float(c) for t, h, c in zip(problem.arc_tail, problem.arc_head, problem.arc_cost)}


def contested(problem: WindowProblem) -> np.ndarray:
    """``(V, R')`` 0/1: the resources held by nodes of two or more objects (one column each)."""
    holds = problem.resources.toarray() > 0
    owners = [set(problem.node_object[holds[:, r]].tolist()) for r in range(holds.shape[1])]
    return holds[:, [r for r, objects in enumerate(owners) if len(objects) >= 2]].astype(int)


def layout_term(problem: WindowProblem, path: np.ndarray) -> float:
    """sum_{(a, b)} mu_ab sum_{m=1}^{M-1} sum_l |(r_a,m+1 - r_b,m+1)_l - (r_a,m - r_b,m)_l|, term by term."""
    r = problem.node_location
    total = 0.0
    for (a, b), mu in zip(problem.layout_pairs, problem.layout_weight):
        for m in range(problem.n_frames - 1):
            for l in range(problem.dimension):
                before = r[path[a, m], l] - r[path[b, m], l]
                after = r[path[a, m + 1], l] - r[path[b, m + 1], l]
                total += mu * abs(after - before)
    return total


def objective(problem: WindowProblem, path: np.ndarray, table: dict[tuple[int, int], float] | None = None) -> float:
    """E(path): arc costs source -> path[n, 0] -> ... -> sink summed by a loop, plus the layout term."""
    table = arc_table(problem) if table is None else table
    total = 0.0
    for n in range(problem.n_objects):
        nodes = [int(problem.source_nodes()[n]), *path[n].tolist(), int(problem.sink_nodes()[n])]
        total += sum(table[step] for step in zip(nodes, nodes[1:]))
    return total + layout_term(problem, path)


def brute_force(problem: WindowProblem) -> tuple[float, np.ndarray]:
    """Optimum and optimal paths by enumerating every feasible joint assignment.

    Each object's paths are enumerated with their arc costs (looked up in ``arc_table``);
    the joint assignments are their Cartesian product, checked against ``contested`` and
    priced with numpy in one go.
    """
    first, sizes = (b[:, 1:-1] for b in problem.blocks())
    table, groups = arc_table(problem), contested(problem)
    sources, sinks = problem.source_nodes(), problem.sink_nodes()
    paths, costs, usage = [], [], []
    for n in range(problem.n_objects):
        options = [range(first[n, m], first[n, m] + sizes[n, m]) for m in range(problem.n_frames)]
        own = np.array(list(itertools.product(*options)))
        steps = [[sources[n], *p, sinks[n]] for p in own.tolist()]
        paths.append(own)
        costs.append(np.array([sum(table[step] for step in zip(s, s[1:])) for s in steps]))
        usage.append(groups[own].sum(axis=1))  # (paths, contested resources)
    grids = np.meshgrid(*[np.arange(len(p)) for p in paths], indexing="ij")
    choice = np.stack([g.ravel() for g in grids], axis=1)  # (J, N)
    total = sum(costs[n][choice[:, n]] for n in range(problem.n_objects))
    used = sum(usage[n][choice[:, n]] for n in range(problem.n_objects))
    feasible = (used <= 1).all(axis=1)
    joint = np.stack([paths[n][choice[:, n]] for n in range(problem.n_objects)], axis=1)  # (J, N, M)
    total = total + _layout_costs(problem, joint)
    total[~feasible] = np.inf
    best = int(np.argmin(total))
    return float(total[best]), joint[best]


def _layout_costs(problem: WindowProblem, joint: np.ndarray) -> np.ndarray:
    """The L1 layout term of each joint assignment ``(J, N, M)``."""
    if len(problem.layout_pairs) == 0:
        return np.zeros(len(joint))
    p = problem.node_location[joint]  # (J, N, M, D)
    a, b = problem.layout_pairs[:, 0], problem.layout_pairs[:, 1]
    change = np.abs(np.diff(p[:, a] - p[:, b], axis=2)).sum(axis=(2, 3))  # (J, P)
    return change @ problem.layout_weight


def assert_feasible(problem: WindowProblem, path: np.ndarray) -> None:
    """One node of the object's own block per frame, consecutive nodes joined by arcs,
    no contested resource held twice."""
    assert path.shape == (problem.n_objects, problem.n_frames)
    assert (problem.node_object[path] == np.arange(problem.n_objects)[:, None]).all()
    assert (problem.node_frame[path] == np.arange(1, problem.n_frames + 1)).all()
    table = arc_table(problem)
    for n in range(problem.n_objects):
        nodes = [int(problem.source_nodes()[n]), *path[n].tolist(), int(problem.sink_nodes()[n])]
        assert all(step in table for step in zip(nodes, nodes[1:])), f"object {n}: a step that is no arc"
    assert (contested(problem)[path.ravel()].sum(axis=0) <= 1).all(), "a contested resource is held twice"
