"""Tiny random windows and an exhaustive solver for them (test helpers)."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from formulations.candidates import WindowCandidates
from formulations.costs import ArcCostWeights
from formulations.network import build_window
from formulations.objective import layout_cost, path_arcs
from formulations.window import WindowProblem


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
    """Optimum and optimal paths by enumerating every feasible joint assignment."""
    first = problem.frame_nodes()
    inner = (problem.node_frame >= 1) & (problem.node_frame <= problem.n_frames)
    block = problem.node_object[inner] * problem.n_frames + problem.node_frame[inner] - 1
    sizes = np.bincount(block, minlength=first.size).reshape(first.shape)
    groups = problem.conflict_groups.toarray()
    per_object = []
    for n in range(problem.n_objects):
        options = [range(first[n, m], first[n, m] + sizes[n, m]) for m in range(problem.n_frames)]
        paths = np.array(list(itertools.product(*options)))
        full = np.zeros((len(paths), problem.n_objects, problem.n_frames), dtype=int)
        full[:] = first  # placeholder rows for other objects, not used
        full[:, n] = paths
        cost = np.array([problem.arc_cost[path_arcs(problem, f)[n]].sum() for f in full])
        per_object.append((paths, cost, groups[:, paths].sum(axis=2)))
    best, best_path = np.inf, None
    for combo in itertools.product(*(range(len(p[0])) for p in per_object)):
        use = sum(per_object[n][2][:, i] for n, i in enumerate(combo))
        if (use > 1).any():
            continue
        path = np.array([per_object[n][0][i] for n, i in enumerate(combo)])
        cost = sum(per_object[n][1][i] for n, i in enumerate(combo))
        cost += layout_cost(problem, path)
        if cost < best:
            best, best_path = cost, path
    return best, best_path
