"""Camera calibrations from files: Pose2Sim/Qualisys TOML, caliscope TOML, markerflow JSON.

Every loader returns ``list[Camera]`` in the file's own length unit unless ``units`` asks
for "m" or "mm" (markerflow's 3D work is in mm: ``load_calibration(path, units="mm")``).
Pose2Sim and caliscope files are in metres. A bad file raises ``InputError`` with one line
naming the file, the camera and the problem.
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from formulations.cameras.camera import Camera
from service.errors import InputError

METRES_PER_UNIT = {"m": 1.0, "mm": 1e-3}
# Pose2Sim's and caliscope's tables: K, distortions, rotation (Rodrigues or 3x3), t, image size.
TOML_KEYS = ("matrix", "distortions", "rotation", "translation", "size")


def _read(path: Path, parse: Callable[[str], Any]) -> Any:
    try:
        return parse(Path(path).read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:  # TOMLDecodeError, JSONDecodeError are ValueErrors
        raise InputError(f"{path}: cannot read calibration: {exc}") from None


def _camera(path: Path, name: str, table: Any, make: Callable[..., Camera], keys: tuple[str, ...]) -> Camera:
    """``make(*(table[key] for key in keys), name)``; a missing key or an invalid camera is an InputError."""
    if not isinstance(table, dict):
        raise InputError(f"{path}: camera {name!r}: expected a table of camera parameters")
    for key in keys:
        if key not in table:
            raise InputError(f"{path}: camera {name!r}: missing key {key!r}")
    try:
        return make(*(table[key] for key in keys), name)
    except ValueError as exc:  # Camera names the camera and the problem
        raise InputError(f"{path}: {exc}") from None


def _in_units(cameras: list[Camera], file_units: str, units: str | None, path: Path) -> list[Camera]:
    if units is None or units == file_units:
        return cameras
    if units not in METRES_PER_UNIT:
        raise InputError(f"{path}: units must be one of {sorted(METRES_PER_UNIT)}, got {units!r}")
    factor = METRES_PER_UNIT[file_units] / METRES_PER_UNIT[units]
    return [camera.scaled(factor) for camera in cameras]


def load_pose2sim_toml(path: Path, units: str | None = None) -> list[Camera]:
    """Pose2Sim's ``Calib_*.toml``: one table per camera (``matrix``, ``distortions`` k1 k2 p1 p2,
    ``rotation`` Rodrigues world -> camera, ``translation`` in m, ``size`` width height)."""
    data = _read(path, tomllib.loads)
    cameras = []
    for section, table in data.items():
        if section == "metadata":
            continue
        name = str(table.get("name", section)) if isinstance(table, dict) else section
        if isinstance(table, dict) and table.get("fisheye", False):
            raise InputError(f"{path}: camera {name!r}: fisheye lenses are not supported")
        cameras.append(_camera(path, name, table, Camera.from_rvec, TOML_KEYS))
    if not cameras:
        raise InputError(f"{path}: no camera tables found")
    return _in_units(cameras, "m", units, path)


def load_caliscope_toml(path: Path, units: str | None = None) -> list[Camera]:
    """caliscope's ``camera_array.toml``: ``[cameras.N]`` with ``matrix``, 5 ``distortions``,
    ``rotation`` (3x3 world -> camera), ``translation`` (m), ``size``. Cameras marked
    ``ignore = true`` are left out; names are ``cam_<cam_id>``."""
    data = _read(path, tomllib.loads)
    tables = data.get("cameras")
    if not isinstance(tables, dict) or not tables:
        raise InputError(f"{path}: missing [cameras.N] tables")
    cameras = []
    for key, table in tables.items():
        name = f"cam_{table.get('cam_id', key) if isinstance(table, dict) else key}"
        if isinstance(table, dict) and table.get("ignore", False):
            continue
        cameras.append(_camera(path, name, table, Camera, TOML_KEYS))
    return _in_units(cameras, "m", units, path)


def load_markerflow_json(path: Path, units: str | None = None) -> list[Camera]:
    """Our JSON: ``{"units": "mm"|"m", "cameras": [{"name", "K", "distortion", "R" or "rvec",
    "t", "image_size"}]}``."""
    data = _read(path, json.loads)
    if not isinstance(data, dict) or not isinstance(data.get("cameras"), list):
        raise InputError(f"{path}: expected an object with a 'cameras' list")
    file_units = data.get("units")
    if file_units not in METRES_PER_UNIT:
        raise InputError(f"{path}: 'units' must be one of {sorted(METRES_PER_UNIT)}, got {file_units!r}")
    cameras = []
    for index, table in enumerate(data["cameras"]):
        name = str(table.get("name", f"#{index}")) if isinstance(table, dict) else f"#{index}"
        rotation, make = ("R", Camera) if isinstance(table, dict) and "R" in table else ("rvec", Camera.from_rvec)
        cameras.append(_camera(path, name, table, make, ("K", "distortion", rotation, "t", "image_size")))
    return _in_units(cameras, file_units, units, path)


def save_markerflow_json(path: Path, cameras: list[Camera], units: str = "mm") -> None:
    """Write ``cameras`` (whose world unit is ``units``) as markerflow JSON; R is kept as a matrix
    so that loading gives back equal cameras."""
    if units not in METRES_PER_UNIT:
        raise ValueError(f"save_markerflow_json: units must be one of {sorted(METRES_PER_UNIT)}, got {units!r}")
    entries = [
        {"name": c.name, "K": c.K.tolist(), "distortion": c.distortion.tolist(), "R": c.R.tolist(),
         "t": c.t.tolist(), "image_size": list(c.image_size)}
        for c in cameras
    ]
    Path(path).write_text(json.dumps({"units": units, "cameras": entries}, indent=2) + "\n")


def load_calibration(path: str | Path, units: str | None = None) -> list[Camera]:
    """Any supported calibration: ``.json`` is markerflow JSON; a ``.toml`` with ``[cameras.N]``
    tables is caliscope, otherwise Pose2Sim."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        return load_markerflow_json(path, units)
    if path.suffix.lower() == ".toml":
        if isinstance(_read(path, tomllib.loads).get("cameras"), dict):
            return load_caliscope_toml(path, units)
        return load_pose2sim_toml(path, units)
    raise InputError(f"{path}: unknown calibration format (expected .json or .toml)")
