"""The capture JSON document: what ``markerflow track`` reads and ``POST /v1/jobs`` takes.

    {
      "units": "mm",                       # of 3D points, first_frame and camera t: "mm" or "m"
      "rate": 120,
      "markers": ["LFHD", "RFHD", ...],
      "first_frame": [[x, y, z], ...],     # labeled frame 0, one row per marker, and/or
      "model": {"version": 1, ...},        # a subject model (markerflow model): it names what frame 0 leaves out
      "points": [[[x, y, z], ...], ...],   # 3D mode: unlabeled points per frame, or
      "cameras": [{"name": "cam1", "K": [[fx, 0, cx], [0, fy, cy], [0, 0, 1]],
                   "distortion": [k1, k2, p1, p2], "R": [[...], [...], [...]] or "rvec": [...],
                   "t": [tx, ty, tz], "image_size": [width, height]}, ...],
      "detections": {"cam1": [[[u, v], ...], ...], ...},   # camera mode: per camera, per frame
      "formulation": "lp-l1" or {"name": "ilp", "time_limit": 10},
      "window": 20,
      "association": "joint-3d",
      "second_pass": true,                 # 3D points: label again from the take's spreads, keep the pass closer to frame 0
      "unnamed_markers": 0                 # 3D points: markers in the points that "markers" leaves out (unnamed tracks)
    }

Frame 0 of ``points``/``detections`` is the labeled frame; with ``model`` (3D points only) the
model's names are used, and ``markers`` and ``first_frame`` may label some of them in frame 0
(a partly labeled frame: the model names the rest; a marker it lacks is added to it as a
single measured in frame 0), or be left out (frame 0 is identified). Every check names the
field path of what is wrong (pydantic's ``loc``), so the HTTP layer can answer 422 with it.
"""

from __future__ import annotations

import json
import math
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, field_validator, model_validator

from formulations.cameras.camera import Camera
from service.capture.capture import ASSOCIATIONS, Capture, LabelingOptions
from service.capture.checks import MAX_COORDINATE, MAX_RATE, MIN_RATE, first_duplicate, first_off_sensor
from service.capture.model_input import check_shared_names, model_names, parse_model, with_model
from service.errors import InputError
from service.io.marker_names import check_marker_names
from service.io.utf8 import utf8_text


def _not_bool(value: object) -> object:
    """JSON ``true`` or a string is not a number: pydantic's lax mode read ``"rate": true`` as 1 Hz. NaN
    and Infinity (Python's JSON reads them) are said as such, not as out of range."""
    if isinstance(value, bool):
        raise ValueError(f"Input should be a number, not {str(value).lower()}")
    if isinstance(value, str):  # lax mode read "120" as 120 Hz
        raise ValueError(f"Input should be a number, not a string ({value!r})")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"Input should be a finite number, not {value}")
    return value


NotBool = BeforeValidator(_not_bool)
# 1e9 (1000 km in mm) bounds every number: sums of squares of larger finite values overflow
# to inf inside the geometry, and no capture is that big.
Finite = Annotated[float, NotBool, Field(allow_inf_nan=False, ge=-MAX_COORDINATE, le=MAX_COORDINATE)]
Point3 = tuple[Finite, Finite, Finite]
Pixel = tuple[Finite, Finite]
MM_PER_UNIT = {"mm": 1.0, "m": 1000.0}
_ONE_ROTATION = "give the world -> camera rotation as exactly one of R or rvec"


class CameraDocument(BaseModel):
    """One calibrated camera in OpenCV conventions (see ``formulations.cameras.camera``)."""

    model_config = ConfigDict(extra="forbid")
    name: str = Field(min_length=1)
    K: tuple[Point3, Point3, Point3]
    distortion: list[Finite] = Field(default_factory=lambda: [0.0] * 5)
    R: tuple[Point3, Point3, Point3] | None = None
    rvec: Point3 | None = None
    t: Point3
    image_size: tuple[Annotated[int, NotBool, Field(gt=0)], Annotated[int, NotBool, Field(gt=0)]]

    @model_validator(mode="after")
    def _camera(self) -> CameraDocument:
        if self.R is not None and self.rvec is not None:
            raise ValueError(_ONE_ROTATION)
        self.camera(1.0)  # K, R and distortion checks, with the camera's own message
        return self

    def camera(self, mm_per_unit: float) -> Camera:
        K, distortion, t = (np.asarray(value, dtype=float) for value in (self.K, self.distortion, self.t))
        if self.R is not None:
            camera = Camera(K, distortion, np.asarray(self.R, dtype=float), t, self.image_size, self.name)
        elif self.rvec is not None:
            camera = Camera.from_rvec(K, distortion, self.rvec, t, self.image_size, self.name)
        else:
            raise ValueError(_ONE_ROTATION)
        return camera.scaled(mm_per_unit)


class CaptureDocument(BaseModel):
    """A capture with the options to label it (module docstring: the JSON layout)."""

    model_config = ConfigDict(extra="forbid")
    units: Literal["mm", "m"] = "mm"
    # Frames per second. C3D stores the rate as float32 (1e308 becomes inf, 1e-300 becomes 0),
    # and no motion capture runs below a frame per 1000 s or above 100 kHz (high-speed video).
    rate: Annotated[float, NotBool] = Field(gt=0, le=MAX_RATE, allow_inf_nan=False)
    markers: list[str] | None = Field(default=None, min_length=1)
    first_frame: list[Point3] | None = None
    model: dict | None = None
    points: list[list[Point3]] | None = None
    cameras: list[CameraDocument] | None = None
    detections: dict[str, list[list[Pixel]]] | None = None
    formulation: str | dict = "lp-l1"
    window: Annotated[int, NotBool] = Field(default=20, ge=2)
    association: Literal[ASSOCIATIONS] = "joint-3d"  # type: ignore[valid-type]
    second_pass: bool = Field(default=True, strict=True)  # "no" and 0 were read as false
    unnamed_markers: Annotated[int, NotBool] = Field(default=0, ge=0)

    @field_validator("rate")
    @classmethod
    def _not_too_slow(cls, rate: float) -> float:
        if rate < MIN_RATE:  # after gt=0, whose message says what a rate of 0 or less lacks
            raise ValueError(f"Input should be greater than or equal to {MIN_RATE:g} (Hz)")
        return rate

    @field_validator("markers")
    @classmethod
    def _unique(cls, markers: list[str] | None) -> list[str] | None:
        seen = set()
        for name in markers or []:
            if name in seen:
                raise ValueError(f"marker name {name!r} appears twice")
            seen.add(name)
        return markers

    @model_validator(mode="after")
    def _consistent(self) -> CaptureDocument:
        if self.model is not None:
            self._check_model()
        elif self.first_frame is None or self.markers is None:
            raise ValueError("give markers and first_frame, or a subject model as model")
        elif len(self.first_frame) != len(self.markers):
            raise ValueError(f"first_frame has {len(self.first_frame)} rows for {len(self.markers)} markers")
        else:
            check_marker_names(self.markers, "markers.{i}")
        if (self.points is None) == (self.detections is None):
            raise ValueError("give exactly one of points (3D mode) or detections (camera mode)")
        if self.detections is not None:
            self._check_detections(self.detections)
        if self.n_frames < 2:
            raise ValueError("a capture needs at least 2 frames (the labeled frame and one more)")
        if self.points is not None and self.unnamed_markers > max(len(frame) for frame in self.points):
            # a marker unnamed is one of the points: more of them than any frame holds is a typo
            raise ValueError(f"unnamed_markers: {self.unnamed_markers} unnamed markers, but no frame of points "
                             f"holds more than {max(len(frame) for frame in self.points)} points")
        return self

    def _check_model(self) -> None:
        if self.points is None:
            raise ValueError("model: labeling from a subject model needs points (3D mode)")
        model = parse_model(json.dumps(self.model), "model")
        check_marker_names(model_names(model), "model (marker {i})")
        if (self.first_frame is None) != (self.markers is None):
            raise ValueError("model: give markers and first_frame together (a partly labeled frame 0), or neither")
        if self.first_frame is not None and self.markers is not None:
            if len(self.first_frame) != len(self.markers):
                raise ValueError(f"first_frame has {len(self.first_frame)} rows for {len(self.markers)} markers")
            check_marker_names(self.markers, "markers.{i}")  # those the model lacks become its singles
            try:  # the model of another marker set named the take its way, and the document's names vanished
                check_shared_names(self.markers, model, "markers")
            except InputError as error:
                raise ValueError(str(error)) from None

    def _check_detections(self, detections: dict[str, list[list[Pixel]]]) -> None:
        if not self.cameras:
            raise ValueError("detections need cameras")
        cameras = {camera.name: camera for camera in self.cameras}
        if len(cameras) != len(self.cameras):
            raise ValueError("camera names must be unique")
        counts = {name: len(frames) for name, frames in detections.items() if frames}  # []: sees nothing
        for name in detections:
            if name not in cameras:
                raise ValueError(f"detections.{name}: camera {name!r} is not in cameras ({', '.join(cameras)})")
        if len(set(counts.values())) > 1:
            listed = ", ".join(f"{name}: {count}" for name, count in counts.items())
            raise ValueError(f"detections: cameras have different frame counts ({listed})")
        for name, frames in detections.items():
            _check_in_image(name, frames, cameras[name].image_size)
        # A camera without detections sees nothing; with fewer than two seeing, nothing can be
        # triangulated and every label (even the given frame 0) would come back empty.
        seeing = [name for name, frames in detections.items() if any(frames)]
        if len(seeing) < 2:
            raise ValueError(f"detections: triangulation needs at least 2 cameras with detections; "
                             f"got {len(seeing)}{f' ({seeing[0]})' if seeing else ''}")

    @property
    def n_frames(self) -> int:
        if self.points is not None:
            return len(self.points)
        return max((len(frames) for frames in (self.detections or {}).values()), default=0)

    def capture(self) -> Capture:
        """The capture in millimetres; cameras without detections see nothing."""
        scale = MM_PER_UNIT[self.units]
        first_frame = np.asarray(self.first_frame or [], dtype=float).reshape(-1, 3) * scale
        if self.model is not None and self.points is not None:
            model = parse_model(json.dumps(self.model), "model")
            frames = [np.asarray(frame, dtype=float).reshape(-1, 3) * scale for frame in self.points]
            labeled = Capture(list(self.markers or []), first_frame, self.rate, points=frames,
                              unnamed_markers=self.unnamed_markers)
            return with_model(labeled, model, keep_labels=True)
        if self.points is not None:
            points = [np.asarray(frame, dtype=float).reshape(-1, 3) * scale for frame in self.points]
            return Capture(list(self.markers or []), first_frame, self.rate, points=points,
                           unnamed_markers=self.unnamed_markers)
        documents, found = self.cameras or [], self.detections or {}  # both there: _consistent checked it
        cameras = [camera.camera(scale) for camera in documents]
        empty: list[list[Pixel]] = [[] for _ in range(self.n_frames)]
        per_camera = [found.get(camera.name) or empty for camera in documents]  # left out or []: sees nothing
        detections = [
            [np.asarray(per_camera[c][f], dtype=float).reshape(-1, 2) for c in range(len(cameras))]
            for f in range(self.n_frames)
        ]
        return Capture(list(self.markers or []), first_frame, self.rate, cameras=cameras, detections=detections,
                       unnamed_markers=self.unnamed_markers)

    @classmethod
    def of(cls, capture: Capture, options: LabelingOptions = LabelingOptions()) -> CaptureDocument:
        """The document of a capture (mm), e.g. to write an example or submit a job."""
        fields = {"rate": capture.rate, "markers": capture.names, "first_frame": capture.first_frame.tolist(),
                  "formulation": options.formulation, "window": options.window, "association": options.association,
                  "second_pass": options.second_pass}
        if capture.points is not None:
            return cls(points=[frame.tolist() for frame in capture.points], unnamed_markers=capture.unnamed_markers,
                       **fields)
        cameras, found = capture.camera_frames()
        documents = [
            {"name": c.name, "K": c.K.tolist(), "distortion": c.distortion.tolist(), "R": c.R.tolist(),
             "t": c.t.tolist(), "image_size": list(c.image_size)}
            for c in cameras
        ]
        detections = {c.name: [frame[i].tolist() for frame in found] for i, c in enumerate(cameras)}
        return cls.model_validate({"cameras": documents, "detections": detections, **fields})

    def options(self) -> LabelingOptions:
        return LabelingOptions(
            formulation=self.formulation, window=self.window, association=self.association, second_pass=self.second_pass,
        )


def _check_in_image(camera: str, frames: list[list[Pixel]], image_size: tuple[int, int]) -> None:
    """Every detection lies on the sensor (``first_off_sensor``), none twice in a frame (``first_duplicate``),
    named by its document path."""
    off = first_off_sensor(frames, image_size)
    if off is not None:
        f, d, (u, v) = off
        raise ValueError(
            f"detections.{camera}.{f}.{d}: ({u:g}, {v:g}) is outside the {image_size[0]}x{image_size[1]} image"
        )
    twice = first_duplicate(frames)
    if twice is not None:
        raise ValueError(f"detections.{camera}.{twice[0]}: detections {twice[1]} and {twice[2]} are the same pixel "
                         "(each listed twice by the export?)")


def read_capture_document(text: str | bytes, source: str) -> CaptureDocument:
    """Parse and check a capture document; an ``InputError`` names ``source`` first."""
    try:
        return capture_document_of(text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text)
    except InputError as error:
        raise InputError(f"{source}: {error}") from None


def capture_document_of(data: bytes) -> CaptureDocument:
    """The checked capture document of ``data`` (a file's bytes, an HTTP body).

    Raises:
        InputError: One line: the field path and what is wrong.
    """
    try:
        return CaptureDocument.model_validate_json(utf8_text(data))
    except ValidationError as error:
        raise InputError(describe_validation_error(error)) from None


def describe_validation_error(error: ValidationError) -> str:
    """The first problem as ``field.path: message`` (and how many more there are)."""
    problems = error.errors(include_url=False)
    first = problems[0]
    path = ".".join(str(part) for part in first["loc"])
    message = first["msg"].removeprefix("Value error, ")
    if first["loc"][:1] == ("detections",) and first["type"] == "too_long":  # OpenPose-style (u, v, c)
        message += " (a detection is [u, v] pixels: leave its confidence out)"
    more = f" (and {len(problems) - 1} more problems)" if len(problems) > 1 else ""
    return f"{path}: {message}{more}" if path else f"{message}{more}"
