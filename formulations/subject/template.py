"""A subject model from a marker-set template and a labeled static take.

Distance variances cannot separate segments on a static take (everything keeps its
distances), so the template says which markers ride on which segment and where each joint
centre is: the mean of named markers of the static take (e.g. the midpoint of the lateral
and medial knee markers, or a lab's own ``RHJC``); centres are not fitted from motion. The
static frames give each segment's marker coordinates by generalised Procrustes
(``fit_segment``). A static take's spread is its noise only; skin moves markers more in
motion, so each spread is taken as sqrt(s_static^2 + skin^2), ``skin`` a property of the
marker set (``skin_mm``: markers on skin, ~5 mm; rigid clusters, less), and a joint's
rms as ``skin`` too. A segment with two markers in the take and a joint to a kept segment is
kept (two markers and the centre make a pose), so a chain of them hangs from a segment of
three; with fewer its markers are singles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from formulations.errors import FormulationError
from formulations.subject.distances import mean_distance
from formulations.subject.joint_rest import rest_rotation
from formulations.subject.model import Joint, Limb, Segment, SingleMarker, SubjectModel
from formulations.subject.segment_fit import SegmentFit, fit_segment

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Template:
    """Segments (name -> template marker names), joints ((segment a, segment b), centre marker names), skin (mm).

    ``joint_rms`` gives, per joint, how far its template centre may be from the true one
    (mm; ``skin_mm`` when the template does not say): a centre guessed from markers off the
    joint (a hip from ASIS and sacrum) is only good to a few centimetres.
    """

    name: str
    segments: dict[str, list[str]]
    joints: list[tuple[tuple[str, str], list[str]]]
    skin_mm: float
    joint_rms: tuple[float, ...] = ()

    @classmethod
    def from_dict(cls, data: dict[str, object], source: str) -> Template:
        """The template of a parsed TOML table. Raises ``FormulationError`` naming ``source`` and the key."""
        segments, joints, skin = data.get("segments"), data.get("joints", []), data.get("skin_mm", 5.0)
        if not isinstance(segments, dict) or not all(
            isinstance(v, list) and all(isinstance(m, str) for m in v) for v in segments.values()
        ):
            raise FormulationError(f"{source}: [segments] must map each segment to a list of marker names")
        if not isinstance(skin, (int, float)) or skin < 0:
            raise FormulationError(f"{source}: skin_mm must be a number >= 0, got {skin!r}")
        parsed, rms = [], []
        for k, joint in enumerate(joints if isinstance(joints, list) else [None]):
            pair = joint.get("segments") if isinstance(joint, dict) else None
            centre = joint.get("centre") if isinstance(joint, dict) else None
            if not (isinstance(pair, list) and len(pair) == 2 and set(pair) <= set(segments)):
                raise FormulationError(f"{source}: joints.{k}.segments must name two segments of [segments]")
            if not (isinstance(centre, list) and centre and all(isinstance(m, str) for m in centre)):
                raise FormulationError(f"{source}: joints.{k}.centre must list the markers whose mean is the centre")
            parsed.append(((str(pair[0]), str(pair[1])), [str(m) for m in centre]))
            error = joint.get("rms_mm", skin) if isinstance(joint, dict) else skin
            if not isinstance(error, (int, float)) or error < 0:
                raise FormulationError(f"{source}: joints.{k}.rms_mm must be a number >= 0, got {error!r}")
            rms.append(float(error))
        return cls(str(data.get("name", source)), {str(k): list(v) for k, v in segments.items()}, parsed, float(skin),
                   tuple(rms))


def base_name(name: str) -> str:
    """A take's marker name without its subject prefix (``Derrick:LASI`` -> ``LASI``)."""
    return name.rsplit(":", 1)[-1]


def fit_template(template: Template, names: list[str], positions: Array) -> SubjectModel:
    """The model of the take's markers (names kept as in the take) under ``template``.

    Raises:
        FormulationError: The take shows fewer than two segments with three markers, or a
            joint's centre markers are missing; the message names them.
    """
    index = {base_name(n): i for i, n in enumerate(names)}
    fits: dict[str, SegmentFit] = {}
    singles: list[int] = []
    pairs: dict[str, list[int]] = {}
    for segment, members in template.segments.items():
        present = [index[m] for m in members if m in index and np.isfinite(positions[:, index[m]]).any()]
        if len(present) >= 3:
            fits[segment] = fit_segment(positions, present)
        elif len(present) == 2:
            pairs[segment] = present
        else:
            singles.extend(present)
    while pairs:  # a pair hung from a kept pair is kept too (a forearm from an upper arm)
        hung = {seg: _pair_centre(template, seg, fits, index, positions) for seg in pairs}
        kept = {seg: centre for seg, centre in hung.items() if centre is not None}
        if not kept:
            break
        for segment, centre in kept.items():
            present = pairs.pop(segment)
            fit = fit_segment(np.concatenate([positions, centre[:, None]], axis=1), present + [len(names)])
            fits[segment] = SegmentFit(present, fit.coordinates[:2], fit.rotation, fit.origin, fit.spread[:2])
    singles.extend(m for present in pairs.values() for m in present)
    if len(fits) < 2:
        raise FormulationError(
            f"template {template.name!r}: the take shows three markers of fewer than two segments "
            f"(it has {len(names)} markers: {', '.join(names[:8])}{' ...' if len(names) > 8 else ''})"
        )
    segments = [
        Segment(name, [names[m] for m in fit.markers], fit.coordinates.round(3).tolist(),
                np.hypot(fit.spread, template.skin_mm).round(3).tolist())
        for name, fit in fits.items()
    ]
    joints, centres = [], {}
    for k, ((a, b), markers) in enumerate(template.joints):
        if a not in fits or b not in fits:
            continue
        missing = [m for m in markers if m not in index]
        if missing:
            raise FormulationError(f"template {template.name!r}: joint {a}-{b} needs markers {', '.join(missing)}")
        world = np.nanmean(positions[:, [index[m] for m in markers]], axis=1)  # (K, 3)
        centres[f"{a}-{b}"] = world
        local = [_in_frame(fits[s], world) for s in (a, b)]
        rms = template.joint_rms[k] if k < len(template.joint_rms) else template.skin_mm
        rest = rest_rotation(fits[a].rotation, fits[b].rotation)
        joints.append(Joint(f"{a}-{b}", (a, b), (local[0], local[1]), rms, rest))
    return SubjectModel(segments, joints, _limbs(joints, centres), _singles(names, singles, positions, fits, template.skin_mm))


def _pair_centre(
    template: Template, segment: str, fits: dict[str, SegmentFit], index: dict[str, int], positions: Array,
) -> Array | None:
    """``(K, 3)`` the centre of a joint from a two-marker segment to a kept segment, if the template has one.

    Two markers and the joint centre are three points: enough for a pose about the joint
    (``joint_place``) once the other segment is posed, so such a segment is kept, not split
    into singles.
    """
    for (a, b), markers in template.joints:
        other = b if a == segment else a if b == segment else None
        if other in fits and all(m in index for m in markers):
            centre: Array = np.nanmean(positions[:, [index[m] for m in markers]], axis=1)
            return centre
    return None


def _in_frame(fit: SegmentFit, world: Array) -> list[float]:
    """The mean over frames of R(k)^T (x(k) - d(k)): a world point in the segment's frame."""
    local = np.einsum("kji,kj->ki", fit.rotation, world - fit.origin)
    return [round(float(v), 3) for v in np.nanmean(local, axis=0)]


def _limbs(joints: list[Joint], centres: dict[str, Array]) -> list[Limb]:
    limbs = []
    for k, first in enumerate(joints):
        for second in joints[k + 1:]:
            shared = set(first.segments) & set(second.segments)
            for segment in shared:
                length = mean_distance(centres[first.name], centres[second.name])
                limbs.append(Limb(segment, (first.name, second.name), round(length, 3)))
    return limbs


def _singles(
    names: list[str], singles: list[int], positions: Array, fits: dict[str, SegmentFit], skin: float,
) -> list[SingleMarker]:
    """Each single's mean distance and sd to the two nearest segment origins."""
    kept = []
    for m in singles:
        stats = sorted(
            (float(np.nanmean(d)), float(np.nanstd(d)), name)
            for name, fit in fits.items() if len(fit.markers) >= 3
            for d in [np.linalg.norm(positions[:, m] - fit.origin, axis=1)]
            if np.isfinite(d).any()
        )[:2]
        kept.append(SingleMarker(names[m], [s for _, _, s in stats], [round(v, 3) for v, _, _ in stats],
                                 [round(float(np.hypot(s, skin)), 3) for _, s, _ in stats]))
    return kept
