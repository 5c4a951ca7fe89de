"""The subject model and its versioned JSON."""

from __future__ import annotations

import json
from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any

import numpy as np

from formulations.errors import FormulationError
from formulations.subject.model_checks import check_model

VERSION = 1
MARKER_RADIUS_MM = 7.0  # a 14 mm marker, the common size on the body


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
