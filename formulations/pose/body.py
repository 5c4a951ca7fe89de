"""The kinematic tree: rigid segments joined by sockets, saddles and hinges under a 6-DOF root.

A node is a joint: its position is where its segment pivots, and its frame is its segment's
frame. Node n sits at ``offset`` in its parent's frame and turns by its own sequential
rotations (``rotation.sequential_rotation``) about its ``axes``: three for a socket, two for
a saddle, one for a hinge, none for a fixed end (a wrist, a toe, the nose). The root (node 0)
also carries the three translation DOF, so the configuration vector is

    X = (t_x, t_y, t_z, root angles, node 1 angles, ..., node J-1 angles),

about 33 DOF for the paper's Fig. 1 body. Joint range limits are hard bounds on each angle;
the root translation is unbounded. Flesh is a set of truncated cones between two nodes.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from formulations.errors import FormulationError
from formulations.pose.rotation import AXES, Array

KINDS = {0: "fixed", 1: "hinge", 2: "saddle", 3: "socket"}
TRANSLATION_DOF = 3


@dataclass(frozen=True)
class Node:
    """A joint: ``offset`` from its parent's joint in the parent's frame, and its rotation DOF with
    their limits (radians; ``lower[k] <= angle_k <= upper[k]``)."""

    name: str
    parent: int
    offset: tuple[float, float, float]
    axes: str = ""
    lower: tuple[float, ...] = ()
    upper: tuple[float, ...] = ()

    @property
    def kind(self) -> str:
        return "root" if self.parent < 0 else KINDS[len(self.axes)]


@dataclass(frozen=True)
class Cone:
    """A truncated cone of flesh from node ``start`` to node ``end`` with radii (at start, at end)."""

    start: int
    end: int
    radii: tuple[float, float]


@dataclass(frozen=True)
class ModelMarker:
    """A skin marker rigidly attached to node ``node`` at ``offset`` in its frame."""

    name: str
    node: int
    offset: tuple[float, float, float]


@dataclass(frozen=True)
class BodyModel:
    """A kinematic tree (node 0 the root; every parent listed before its children), its cones and markers."""

    nodes: tuple[Node, ...]
    cones: tuple[Cone, ...] = ()
    markers: tuple[ModelMarker, ...] = ()

    def __post_init__(self) -> None:
        if not self.nodes or self.nodes[0].parent != -1:
            raise FormulationError("body model: node 0 must be the root (parent -1)")
        for index, node in enumerate(self.nodes):
            if index and not 0 <= node.parent < index:
                raise FormulationError(f"body model: node {node.name!r} must come after its parent")
            if len(node.axes) > 3 or set(node.axes) - set(AXES) or not len(node.lower) == len(node.upper) == len(node.axes):
                raise FormulationError(f"body model: node {node.name!r} needs up to 3 axes of x, y, z with one limit pair each")
            if any(lo > hi for lo, hi in zip(node.lower, node.upper)):
                raise FormulationError(f"body model: node {node.name!r} has a lower limit above its upper limit")
        for cone in self.cones:
            if not (0 <= cone.start < len(self.nodes) and 0 <= cone.end < len(self.nodes)):
                raise FormulationError(f"body model: cone {cone} names a node that does not exist")

    @property
    def names(self) -> list[str]:
        return [node.name for node in self.nodes]

    def index(self, name: str) -> int:
        return self.names.index(name)

    @property
    def columns(self) -> list[int]:
        """The column of X where each node's first angle sits."""
        columns, column = [], TRANSLATION_DOF
        for node in self.nodes:
            columns.append(column)
            column += len(node.axes)
        return columns

    @property
    def dof(self) -> int:
        return TRANSLATION_DOF + sum(len(node.axes) for node in self.nodes)

    @property
    def lower(self) -> Array:
        return np.concatenate([np.full(TRANSLATION_DOF, -np.inf), *[np.array(n.lower, dtype=float) for n in self.nodes]])

    @property
    def upper(self) -> Array:
        return np.concatenate([np.full(TRANSLATION_DOF, np.inf), *[np.array(n.upper, dtype=float) for n in self.nodes]])

    def clip(self, configurations: Array) -> Array:
        """Configurations ``(N, D)`` moved onto the joint limits where they cross them."""
        clipped: Array = np.clip(configurations, self.lower, self.upper)
        return clipped

    def scaled(self, factor: float) -> BodyModel:
        """The same body in a length unit ``factor`` times smaller (m -> mm: 1000); angles unchanged."""
        def times(v: tuple[float, ...]) -> tuple[float, float, float]:
            return (v[0] * factor, v[1] * factor, v[2] * factor)

        return BodyModel(
            tuple(replace(n, offset=times(n.offset)) for n in self.nodes),
            tuple(replace(c, radii=(c.radii[0] * factor, c.radii[1] * factor)) for c in self.cones),
            tuple(replace(m, offset=times(m.offset)) for m in self.markers),
        )
