"""Forward kinematics of a body model, vectorised over particles.

For node n with parent p, offset o_n (in p's frame) and local rotation L_n(X) (its sequential
axis rotations),

    R_n = R_p L_n,    x_n = x_p + R_p o_n,

and for the root x_0 = (t_x, t_y, t_z) + o_0, R_0 = L_0. One pass over the nodes, each step a
batched (N, 3, 3) product over all N particles at once; a marker m on node n sits at
x_n + R_n o_m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from formulations.pose.body import TRANSLATION_DOF, BodyModel
from formulations.pose.rotation import Array, sequential_rotation


@dataclass(frozen=True)
class Posed:
    """All particles' joint positions ``(N, J, 3)`` and segment frames ``(N, J, 3, 3)`` (columns: the
    segment's x, y, z axes in the world)."""

    positions: Array
    rotations: Array


def forward_kinematics(model: BodyModel, configurations: Array) -> Posed:
    """Joint positions and frames of ``(N, D)`` configurations (one row per particle)."""
    X = np.atleast_2d(np.asarray(configurations, dtype=float))
    count = len(X)
    positions = np.empty((count, len(model.nodes), 3))
    rotations = np.empty((count, len(model.nodes), 3, 3))
    for index, (node, column) in enumerate(zip(model.nodes, model.columns)):
        local = sequential_rotation(node.axes, X[:, column:column + len(node.axes)])
        offset = np.asarray(node.offset, dtype=float)
        if node.parent < 0:
            positions[:, index] = X[:, :TRANSLATION_DOF] + offset
            rotations[:, index] = local
        else:
            parent = rotations[:, node.parent]
            positions[:, index] = positions[:, node.parent] + parent @ offset
            rotations[:, index] = parent @ local
    return Posed(positions, rotations)


def marker_positions(model: BodyModel, posed: Posed) -> Array:
    """``(N, K, 3)`` world positions of the model's K markers."""
    if not model.markers:
        return np.empty((len(posed.positions), 0, 3))
    nodes = np.array([marker.node for marker in model.markers])
    offsets = np.array([marker.offset for marker in model.markers], dtype=float)
    markers: Array = posed.positions[:, nodes] + np.einsum("nkij,kj->nki", posed.rotations[:, nodes], offsets)
    return markers
