"""Tiny random windows and an exhaustive solver for them (test helpers)."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from formulations.window.build import build_window
from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights
from formulations.window.objective import conflicts, path_arcs
from formulations.window.problem import WindowProblem


def random_window(
    seed: int, n_objects: int = 3, n_frames: int = 3, n_points: int = 4, per_object: int = 2,
    mu: float = 0.0, dim: int = 2,
) -> WindowProblem:
    """Objects drawing ``per_object`` candidates each frame from ``n_points`` shared points."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0, 10, size=(n_frames, n_points, dim))
    objects, frames, ids = [], [], []
    for n in range(n_objects):
        for m in range(n_frames):
            chosen = rng.choice(n_points, size=per_object, replace=False)
            objects += [n] * per_object
            frames += [m + 1] * per_object
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
    )
    pairs = np.array(list(itertools.combinations(range(n_objects), 2))) if mu > 0 else None
    weights = ArcCostWeights(displacement=1.0, reappear=3.0, disappear=3.0)
    return build_window(candidates, weights, pairs, mu)[0]


def brute_force(problem: WindowProblem) -> tuple[float, np.ndarray]:
    """Optimum and optimal paths by enumerating every feasible joint assignment.

    Each object's paths are enumerated with their arc costs; the joint assignments are
    their Cartesian product, checked and priced with numpy in one go.
    """
    first, sizes = (b[:, 1:-1] for b in problem.blocks())
    groups = problem.conflict_groups.toarray()
    paths, costs, usage = [], [], []
    for n in range(problem.n_objects):
        options = [range(first[n, m], first[n, m] + sizes[n, m]) for m in range(problem.n_frames)]
        own = np.array(list(itertools.product(*options)))
        full = np.repeat(first[None], len(own), axis=0)
        full[:, n] = own
        arcs = np.stack([path_arcs(problem, f)[n] for f in full])
        paths.append(own)
        costs.append(problem.arc_cost[arcs].sum(axis=1))
        usage.append(groups[:, own].sum(axis=2).T)  # (paths, groups)
    grids = np.meshgrid(*[np.arange(len(p)) for p in paths], indexing="ij")
    choice = np.stack([g.ravel() for g in grids], axis=1)  # (J, N)
    total = sum(costs[n][choice[:, n]] for n in range(problem.n_objects))
    used = sum(usage[n][choice[:, n]] for n in range(problem.n_objects))
    feasible = (used <= 1).all(axis=1) if groups.shape[0] else np.ones(len(choice), bool)
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


def assert_feasible(problem, path):
    """One node of the object's own block per frame, no conflict group used twice."""
    assert path.shape == (problem.n_objects, problem.n_frames)
    assert (problem.node_object[path] == np.arange(problem.n_objects)[:, None]).all()
    assert (problem.node_frame[path] == np.arange(1, problem.n_frames + 1)).all()
    assert len(conflicts(problem, path)) == 0
