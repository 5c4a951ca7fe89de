"""The subject model and its versioned JSON."""

from __future__ import annotations

import json
from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any

import numpy as np

from formulations.errors import FormulationError

VERSION = 1
MARKER_RADIUS_MM = 7.0  # a 14 mm marker, the common size on the body
MAX_COORDINATE_MM = 5000.0  # a marker or joint centre in its segment's frame: within a body's size
MAX_SPREAD_MM = 100.0  # a marker moving more than this on its segment is not on a rigid segment
ROTATION_TOLERANCE = 1e-3  # |R R^T - I| and |det R - 1| of a rest rotation as JSON rounds it


@dataclass(frozen=True)
class Segment:
    """A rigid segment: its markers, their coordinates in its frame (mm) and their spread (RMS mm)."""

    name: str
    markers: list[str]
    coordinates: list[list[float]]
    spread: list[float]


@dataclass(frozen=True)
class Joint:
    """A ball joint: the two segments and the centre in each one's frame (mm); its fit RMS (mm);
    ``rest``, the second segment's usual rotation in the first's frame (``joint_rest``; None in
    models written before it was kept, which then cannot tell a near-isosceles pair's readings apart)."""

    name: str
    segments: tuple[str, str]
    centres: tuple[list[float], list[float]]
    rms: float
    rest: list[list[float]] | None = None


@dataclass(frozen=True)
class Limb:
    """The length of a segment between two of its joints: the mean distance of their centres (mm)."""

    segment: str
    joints: tuple[str, str]
    length: float


@dataclass(frozen=True)
class SingleMarker:
    """A marker on no segment, modelled by its mean distance (mm) and its sd to the nearest segments' origins."""

    marker: str
    segments: list[str]
    distances: list[float]
    sd: list[float]


MODEL_KEYS = ("segments", "joints", "limbs", "singles")  # what a version-1 model holds


@dataclass(frozen=True)
class SubjectModel:
    """Which markers ride on which segment, the joints, the limb lengths and the marker radius."""

    segments: list[Segment]
    joints: list[Joint]
    limbs: list[Limb]
    singles: list[SingleMarker]
    marker_radius: float = MARKER_RADIUS_MM

    def to_json(self) -> str:
        return json.dumps({"version": VERSION, **asdict(self)}, indent=1)

    @staticmethod
    def from_json(text: str) -> SubjectModel:
        """Raises ``FormulationError`` (one line) on text that is not a version-1 subject model."""
        try:
            data = json.loads(text)
        except ValueError as error:
            raise FormulationError(f"subject model is not JSON ({error})") from None
        if not isinstance(data, dict) or data.get("version") != VERSION:
            found = data.get("version") if isinstance(data, dict) else None
            raise FormulationError(f"subject model version {found!r} is not supported (expected {VERSION})")
        unknown = sorted(set(data) - {"version", "marker_radius", *MODEL_KEYS})
        if unknown:
            raise FormulationError(f"subject model has an unknown field {unknown[0]!r} "
                                   f"(a model holds version, {', '.join(MODEL_KEYS)}, marker_radius)")
        if not isinstance(data.get("marker_radius", 0.0), int | float) or isinstance(data.get("marker_radius"), bool):
            raise FormulationError(f"subject model's marker_radius must be a number (mm), got {data['marker_radius']!r}")
        missing = [key for key in MODEL_KEYS if key not in data]
        if missing:
            raise FormulationError(f"subject model is malformed: it has no {', '.join(repr(k) for k in missing)} "
                                   f"(a model holds {', '.join(MODEL_KEYS)})")
        try:
            return _decode(data)
        except KeyError as error:  # a field of one entry: name it, not the exception
            raise FormulationError(f"subject model is malformed: an entry lacks its {error} field") from None
        except (TypeError, ValueError) as error:
            raise FormulationError(f"subject model is malformed: {error}") from None


def _decode(data: dict[str, Any]) -> SubjectModel:
    joints = [
        Joint(j["name"], (j["segments"][0], j["segments"][1]), (j["centres"][0], j["centres"][1]), float(j["rms"]),
              j.get("rest"))
        for j in data["joints"]
    ]
    limbs = [Limb(b["segment"], (b["joints"][0], b["joints"][1]), float(b["length"])) for b in data["limbs"]]
    model = SubjectModel(
        [_entry(Segment, s) for s in data["segments"]], joints, limbs,
        [_entry(SingleMarker, m) for m in data["singles"]], float(data["marker_radius"]),
    )
    names = {s.name for s in model.segments}
    if not (np.isfinite(model.marker_radius) and model.marker_radius >= 0):
        raise ValueError(f"marker_radius must be a finite number >= 0 (mm), got {model.marker_radius}")
    for segment in model.segments:
        if not segment.markers:
            raise ValueError(f"segment {segment.name!r} has no markers")
        if len(segment.coordinates) != len(segment.markers) or any(len(c) != 3 for c in segment.coordinates):
            raise ValueError(f"segment {segment.name!r}: coordinates do not match its markers")
        if len(segment.spread) != len(segment.markers):
            raise ValueError(f"segment {segment.name!r}: spread has {len(segment.spread)} values for "
                             f"{len(segment.markers)} markers")
        _finite(segment.coordinates, f"segment {segment.name!r}: coordinates")
        _non_negative(segment.spread, f"segment {segment.name!r}: spread")
    for joint in model.joints:
        if not set(joint.segments) <= names:
            raise ValueError(f"joint {joint.name!r} names an unknown segment")
        if joint.rest is not None and np.asarray(joint.rest, dtype=float).shape != (3, 3):
            raise ValueError(f"joint {joint.name!r}: rest is not a 3 x 3 rotation")
        _finite([*joint.centres, *(joint.rest or [])], f"joint {joint.name!r}: centres and rest")
        _non_negative([joint.rms], f"joint {joint.name!r}: rms")
    for limb in model.limbs:
        _finite([limb.length], f"limb of segment {limb.segment!r}: length")
    for single in model.singles:
        unknown = [name for name in single.segments if name not in names]
        if unknown or not (len(single.segments) == len(single.distances) == len(single.sd)):
            raise ValueError(f"single marker {single.marker!r}: " + (f"segment {unknown[0]!r} is not in the model"
                             if unknown else "segments, distances and sd differ in length"))
        _finite(single.distances, f"single marker {single.marker!r}: distances")
        _non_negative(single.sd, f"single marker {single.marker!r}: sd")
    check_model(model)
    return model


def _entry(kind: type, fields_of: Any) -> Any:
    """``kind(**fields_of)``, naming a missing or unknown field (not ``__init__``'s wording)."""
    expected = {f.name for f in fields(kind)}
    required = {f.name for f in fields(kind) if f.default is MISSING}
    given = set(fields_of) if isinstance(fields_of, dict) else set()
    if not isinstance(fields_of, dict) or required - given or given - expected:
        what = kind.__name__.lower().replace("singlemarker", "single marker")
        problem = (f"lacks {sorted(required - given)[0]!r}" if required - given else
                   f"has an unknown field {sorted(given - expected)[0]!r}" if given - expected else "is not an object")
        raise ValueError(f"a {what} {problem} (it holds {', '.join(f.name for f in fields(kind))})")
    return kind(**fields_of)


def _non_negative(values: Any, what: str) -> None:
    """A spread, an sd or an RMS is a length >= 0 (a negative one made gates that pass nothing)."""
    array = np.asarray(values, dtype=float)
    if not (np.isfinite(array) & (array >= 0)).all():
        raise ValueError(f"{what} must be finite numbers >= 0 (mm)")


def _finite(values: Any, what: str) -> None:
    """JSON takes NaN and Infinity; a model's geometry cannot (an SVD of them fails far from the file)."""
    if not np.isfinite(np.asarray(values, dtype=float)).all():
        raise ValueError(f"{what} must be finite numbers")


# What a model file must hold beyond its fields' types. A lab may edit the JSON by hand, and
# each of these was accepted and then failed far from the file: a coordinate of 1e300 raised
# an IndexError inside the labeler, a spread of 1 m made every point a candidate of every
# marker (17 s for 5 frames), a joint closing a loop broke the skeleton's dynamic programming
# (``tree_choice`` assumes a forest), a limb between unknown joints was printed as the subject's.


def check_model(model: SubjectModel) -> None:
    """Raises ``ValueError`` (one line naming the entry) on a model no body has."""
    for segment in model.segments:
        _within(segment.coordinates, MAX_COORDINATE_MM, f"segment {segment.name!r}: coordinates")
        _within(segment.spread, MAX_SPREAD_MM, f"segment {segment.name!r}: spread")
    for joint in model.joints:
        _within(list(joint.centres), MAX_COORDINATE_MM, f"joint {joint.name!r}: centres")
        _within([joint.rms], MAX_SPREAD_MM, f"joint {joint.name!r}: rms")
        if joint.rest is not None and not _is_rotation(np.asarray(joint.rest, dtype=float)):
            raise ValueError(f"joint {joint.name!r}: rest is not a rotation (orthonormal, determinant 1)")
    for single in model.singles:
        # a single's distance to a segment spans joints: its sd may be a limb's swing, not a spread
        _within(single.sd, MAX_COORDINATE_MM, f"single marker {single.marker!r}: sd")
        _within(single.distances, MAX_COORDINATE_MM, f"single marker {single.marker!r}: distances")
    _check_forest(model)
    _check_limbs(model)


def _within(values: object, bound: float, what: str) -> None:
    if (np.abs(np.asarray(values, dtype=float)) > bound).any():
        raise ValueError(f"{what} must be within {bound:g} mm")


def _is_rotation(rest: np.ndarray) -> bool:
    return bool(np.abs(rest @ rest.T - np.eye(3)).max() <= ROTATION_TOLERANCE
                and abs(np.linalg.det(rest) - 1.0) <= ROTATION_TOLERANCE)


def _check_forest(model: SubjectModel) -> None:
    """Joints join two different segments, and no chain of joints comes back to where it began."""
    root = {segment.name: segment.name for segment in model.segments}

    def find(name: str) -> str:
        while root[name] != name:
            name = root[name]
        return name

    for joint in model.joints:
        a, b = joint.segments
        if a == b:
            raise ValueError(f"joint {joint.name!r} joins segment {a!r} to itself")
        if find(a) == find(b):
            raise ValueError(f"joint {joint.name!r} closes a loop of joints through {a!r} and {b!r} "
                             "(a skeleton's joints form a tree)")
        root[find(a)] = find(b)


def _check_limbs(model: SubjectModel) -> None:
    """A limb is a length >= 0 of its segment between two of that segment's joints."""
    joints = {joint.name: joint for joint in model.joints}
    for limb in model.limbs:
        what = f"limb of segment {limb.segment!r}"
        unknown = [name for name in limb.joints if name not in joints]
        if unknown:
            raise ValueError(f"{what}: joint {unknown[0]!r} is not in the model")
        if any(limb.segment not in joints[name].segments for name in limb.joints):
            raise ValueError(f"{what}: its joints {limb.joints[0]!r} and {limb.joints[1]!r} are not both on it")
        if not 0 <= limb.length <= MAX_COORDINATE_MM:
            raise ValueError(f"{what}: length must be >= 0 and within {MAX_COORDINATE_MM:g} mm, got {limb.length:g}")
