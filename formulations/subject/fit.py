"""Fit a subject model to labeled trajectories (Ringer & Lasenby 2004, Secs. 3-4)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.errors import FormulationError
from formulations.subject.distances import distance_spread
from formulations.subject.grouping import Grouping, group_markers, settle
from formulations.subject.joint_fit import JointFit
from formulations.subject.joint_rest import rest_rotation
from formulations.subject.model import Joint, Limb, Segment, SingleMarker, SubjectModel
from formulations.subject.pair_fit import attach_pairs
from formulations.subject.segment_fit import SegmentFit, fit_segment
from formulations.subject.skeleton import Skeleton, build_skeleton, limb_lengths

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FitOptions:
    """Tolerances of the fit (mm, frames)."""

    rigid_sd: float = 10.0  # sd of a distance on one segment: noise and skin motion
    joint_rms: float = 25.0  # rms of a ball-joint fit; above it two segments are not jointed
    min_frames: int = 20  # frames two markers must be seen together to be compared


@dataclass(frozen=True)
class SubjectFit:
    """The model, the marker grouping it came from, and the joint-centre trajectories ``(K, 3)`` by joint name."""

    model: SubjectModel
    grouping: Grouping
    centres: dict[str, Array]


def fit_subject(names: list[str], positions: Array, options: FitOptions = FitOptions()) -> SubjectFit:
    """Group markers by D, fit segments and joints, and keep the markers on no segment.

    Raises:
        FormulationError: too few frames, or a take too static (or too gappy) to separate
            at least two jointed segments; the message names the markers and why.
    """
    frames = len(positions)
    if frames < options.min_frames:
        raise FormulationError(f"only {frames} frames; a subject model needs at least {options.min_frames}")
    spread, _ = distance_spread(positions, options.min_frames)
    grouping = settle(group_markers(spread, options.rigid_sd), spread, options.rigid_sd)
    groups = [g for g in grouping.groups if len(g) >= 3]
    _check_separable(names, groups, spread, frames, options)
    segments = [fit_segment(positions, g) for g in groups]
    posed_alone = len(segments)  # singles are measured from these: a frame poses them without joints
    pairs = [g for g in grouping.groups if len(g) == 2]
    segments = attach_pairs(pairs, segments, positions, options.joint_rms, options.min_frames)
    groups = [s.markers for s in segments]
    skeleton = build_skeleton(segments, positions, options.joint_rms)
    if not skeleton.joints:
        listed = "; ".join(", ".join(names[m] for m in g) for g in groups)
        raise FormulationError(
            f"no two of the segments [{listed}] turn about a common centre (joint rms > {options.joint_rms:g} mm)"
        )
    seg_names = [names[g[0]] for g in groups]
    on_segment = {m for g in groups for m in g}
    singles = [_single(names[m], positions[:, m], segments[:posed_alone], seg_names) for m in range(len(names))
               if m not in on_segment]
    model = SubjectModel(
        [_segment(s, names, n) for s, n in zip(segments, seg_names)],
        [_joint(a, b, fit, seg_names, segments) for a, b, fit in skeleton.joints],
        _limbs(skeleton, seg_names),
        [s for s in singles if s is not None],
    )
    return SubjectFit(model, grouping, {j.name: fit.trajectory for j, (_, _, fit) in zip(model.joints, skeleton.joints)})


def _check_separable(names: list[str], groups: list[list[int]], spread: Array, frames: int, options: FitOptions) -> None:
    """Refuse a take whose distances cannot separate the body's segments.

    One "segment" holding more than half the markers is a body that kept still, whatever
    else moved (a static trial's head nodding beside 46 markers fitted as one rigid body,
    jointed to it); on the dynamic takes of ../shared/data the largest holds 7-31 %.
    """
    too_big = [g for g in groups if len(g) > len(names) / 2]
    if too_big:
        g = too_big[0]
        worst = spread[np.ix_(g, g)].max()
        raise FormulationError(
            f"too static to separate segments: markers {', '.join(names[m] for m in g)} keep their mutual distances "
            f"(sd at most {worst:.1f} mm <= {options.rigid_sd:g} mm) over {frames} frames; fit on a range-of-motion take"
        )
    if len(groups) >= 2:
        return
    loose = [names[m] for m in range(len(names)) if not any(m in g for g in groups)]
    raise FormulationError(
        f"cannot group markers {', '.join(loose)}: fewer than 3 keep a rigid distance (sd <= {options.rigid_sd:g} mm, "
        f"seen together in >= {options.min_frames} of {frames} frames) with one another; two rigid segments are needed"
    )


def _segment(fit: SegmentFit, names: list[str], name: str) -> Segment:
    return Segment(name, [names[m] for m in fit.markers], fit.coordinates.round(3).tolist(), fit.spread.round(3).tolist())


def _joint(a: int, b: int, fit: JointFit, seg_names: list[str], segments: list[SegmentFit]) -> Joint:
    return Joint(
        f"{seg_names[a]}-{seg_names[b]}", (seg_names[a], seg_names[b]),
        (fit.centre_a.round(3).tolist(), fit.centre_b.round(3).tolist()), round(fit.rms, 3),
        rest_rotation(segments[a].rotation, segments[b].rotation),
    )


def _limbs(skeleton: Skeleton, seg_names: list[str]) -> list[Limb]:
    def joint_name(i: int) -> str:
        a, b, _ = skeleton.joints[i]
        return f"{seg_names[a]}-{seg_names[b]}"

    return [
        Limb(seg_names[s], (joint_name(i), joint_name(j)), round(length, 3))
        for s, i, j, length in limb_lengths(skeleton, len(seg_names))
    ]


def _single(name: str, track: Array, segments: list[SegmentFit], seg_names: list[str], nearest: int = 2) -> SingleMarker | None:
    """The marker's mean distance and sd to the ``nearest`` segment origins; None if never seen with one."""
    stats = []
    for fit, seg in zip(segments, seg_names):
        d = np.linalg.norm(track - fit.origin, axis=1)
        d = d[np.isfinite(d)]
        if d.size:
            stats.append((float(d.mean()), float(d.std()), seg))
    if not stats:
        return None
    stats.sort()
    chosen = stats[:nearest]
    return SingleMarker(name, [s for _, _, s in chosen], [round(m, 3) for m, _, _ in chosen], [round(s, 3) for _, s, _ in chosen])
