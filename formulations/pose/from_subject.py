"""A body model built from a fitted subject model (Ringer & Lasenby 2004; ``formulations.subject``).

The segment with the most joints is the root; the others hang off it through their ball
joints, found breadth first (the subject model's joints form no loops). A child segment's
node sits at its joint's centre and its frame is the segment's own frame, so at rest (all
angles 0) every segment keeps the orientation it had in the fit's frames; its offset from the
parent's node is the centre in the parent's frame minus the parent node's origin there.
Markers ride at their fitted coordinates relative to their segment's node. Ball joints are
sockets with the full range (a fit from marker data gives no anatomical limits). Each limb
(a segment between two joints) becomes a cone whose radius is the median distance of the
segment's markers from its axis, less the marker radius. Nodes are named after the joints,
so a joint renamed like a BODY_25B keypoint (e.g. "RKnee") carries that keypoint.
"""

from __future__ import annotations

import numpy as np

from formulations.errors import FormulationError
from formulations.pose.body import BodyModel, Cone, ModelMarker, Node
from formulations.subject.model import SubjectModel

FULL = (-np.pi, np.pi)
MIN_RADIUS_MM = 20.0


def subject_body(subject: SubjectModel, metres_per_unit: float = 1e-3) -> BodyModel:
    """The body of ``subject`` (mm) in a length unit of ``metres_per_unit`` metres."""
    if not subject.joints:
        raise FormulationError("subject model has no joints: nothing to articulate")
    segments = {s.name: s for s in subject.segments}
    degree = {name: sum(name in j.segments for j in subject.joints) for name in segments}
    root = max(segments, key=lambda name: degree[name])
    nodes = [Node(root, -1, (0.0, 0.0, 0.0), "zyx", (-np.inf, -np.pi / 2, -np.inf), (np.inf, np.pi / 2, np.inf))]
    origin = {root: np.zeros(3)}  # each placed segment's node, in its own frame (mm)
    node_of = {root: 0}
    joint_node: dict[str, int] = {}
    frontier = [root]
    while frontier:
        parent = frontier.pop(0)
        for joint in subject.joints:
            if parent not in joint.segments:
                continue
            side = joint.segments.index(parent)
            child = joint.segments[1 - side]
            if child in node_of:
                continue
            offset = np.asarray(joint.centres[side]) - origin[parent]
            nodes.append(Node(joint.name, node_of[parent], (float(offset[0]), float(offset[1]), float(offset[2])), "zxy",
                              (FULL[0],) * 3, (FULL[1],) * 3))
            node_of[child] = joint_node[joint.name] = len(nodes) - 1
            origin[child] = np.asarray(joint.centres[1 - side], dtype=float)
            frontier.append(child)
    markers = tuple(
        ModelMarker(m, node_of[s.name], tuple(float(v) for v in np.asarray(c) - origin[s.name]))  # type: ignore[arg-type]
        for s in subject.segments if s.name in node_of for m, c in zip(s.markers, s.coordinates)
    )
    cones = tuple(_cone(subject, limb.segment, limb.joints, joint_node) for limb in subject.limbs
                  if limb.segment in node_of and all(j in joint_node for j in limb.joints))
    return BodyModel(tuple(nodes), tuple(c for c in cones if c is not None), markers).scaled(1e-3 / metres_per_unit)


def _cone(subject: SubjectModel, segment: str, joints: tuple[str, str], joint_node: dict[str, int]) -> Cone | None:
    """The limb's cone between its two joints' nodes (each joint's node is its child segment's node)."""
    own = {j.name: j for j in subject.joints}
    ends, centres = [], []
    for name in joints:
        joint = own[name]
        centres.append(np.asarray(joint.centres[joint.segments.index(segment)], dtype=float))
        ends.append(joint_node[name])
    if ends[0] == ends[1]:
        return None
    seg = next(s for s in subject.segments if s.name == segment)
    axis = (centres[1] - centres[0]) / (np.linalg.norm(centres[1] - centres[0]) or 1.0)
    relative = np.asarray(seg.coordinates, dtype=float) - centres[0]
    distance = np.linalg.norm(relative - np.outer(relative @ axis, axis), axis=1)
    radius = max(float(np.median(distance)) - subject.marker_radius, MIN_RADIUS_MM)
    return Cone(ends[0], ends[1], (radius, radius))
