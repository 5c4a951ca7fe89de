"""A capture to label, in either input mode, and how to label it.

A capture is what a lab hands markerflow: marker names, the labeled first frame (names +
3D positions, as in Ringer & Lasenby 2004: the first frame has no prediction, so the user
or a template fit labels it), and per frame either unlabeled 3D points or, with calibrated
cameras, 2D detections per camera. Frame 0 of the points/detections is the labeled frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from formulations.cameras.camera import Camera
from formulations.methods.formulation import Formulation, plain
from formulations.subject.model import SubjectModel
from service.capture.checks import (
    checked_count,
    checked_detections,
    checked_first_frame,
    checked_frames,
    checked_names,
    checked_rate,
    first_duplicate,
    first_off_sensor,
)
from service.capture.formulation_spec import resolve_formulation
from service.capture.frame0_points import check_frame0_points
from service.capture.reprojection import frame0_distances, frame0_offsets, frame0_problem
from service.errors import InputError

ASSOCIATIONS = ("joint-3d", "per-camera")


@dataclass(frozen=True)
class LabelingOptions:
    """How to label a capture.

    Attributes:
        formulation: A formulation name, a ``[formulation]`` table (``{"name": ..., **parameters}``),
            or a formulation instance.
        window: Frames per window, template included.
        association: Camera mode only: ``"joint-3d"`` (cross-camera 3D points labeled by the
            window LP) or ``"per-camera"`` (2D window LP per camera, then triangulation).
        layout_weight: mu of the L1 layout term between rigid neighbours coupled by shared
            candidates, 3D points (and joint-3d) only; 0, the default, leaves it out.
        best_view_switch_cost: Camera mode: lambda of each marker's best-view DP (Jiang Sec.
            III, ``service.best_view.markers``), the price of a camera switch in frames of
            the best view; default 1.
        best_view_window: Camera mode: N, frames per best-view window; default 30.
        second_pass: 3D points without a subject model: label the take again from the
            distance spreads the first labeling measured, and keep the labeling whose rigid
            pairs agree better with the first frame (``service.labeling.second_pass``); up to
            twice the time.
        rival_reading: With a second pass that runs (a doubtful take) and a formulation that
            looks ahead: read the take frame by frame as well, and take the marker groups whose
            rigid pairs that reading bends less (``service.labeling.rival_reading``); about a
            third more time.
        mht_reading: Where the frame-by-frame reading runs, on 3D points without a subject
            model: read the take by ``mht`` as well and take, after it, the marker groups whose
            rigid pairs that reading bends less (``service.labeling.hypothesis_reading``). Off
            by default: it about doubles the time of a doubtful take (real 03_rolling from
            frame 562: 31-38 -> 71-78 s).
    """

    formulation: str | dict | Formulation = "lp-l1"
    window: int = 20
    association: str = "joint-3d"
    layout_weight: float = 0.0
    best_view_switch_cost: float = 1.0
    best_view_window: int = 30
    second_pass: bool = True
    rival_reading: bool = True
    mht_reading: bool = False

    def __post_init__(self) -> None:
        for option in fields(self):  # a notebook's np.float32(1.0) or np.bool_(False) is a plain value
            object.__setattr__(self, option.name, plain(getattr(self, option.name)))
        if not isinstance(self.formulation, (str, dict, Formulation)):
            raise InputError(f"formulation must be a name, a table or a Formulation, got {self.formulation!r}")
        if not isinstance(self.formulation, Formulation):  # a name or a table is checked now, not at labeling
            resolve_formulation(self.formulation)
        checked_count(self.window, "window", least=2)
        checked_count(self.best_view_window, "best_view_window", least=1)
        if self.association not in ASSOCIATIONS:
            raise InputError(f"association must be one of {', '.join(ASSOCIATIONS)}, got {self.association!r}")
        for name in ("layout_weight", "best_view_switch_cost"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value < float("inf"):
                raise InputError(f"{name} must be a finite number of at least 0, got {value!r}")
        for name in ("second_pass", "rival_reading", "mht_reading"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(f"{name} must be True or False, got {getattr(self, name)!r}")


@dataclass
class Capture:
    """Unlabeled frames and the labeled first frame (millimetres, pixels).

    Attributes:
        names: Marker names.
        first_frame: ``(N, 3)`` labeled positions of frame 0, mm.
        rate: Frames per second.
        points: 3D mode: per frame a ``(P, 3)`` array of unlabeled points, mm.
        cameras: Camera mode: the calibrated cameras (world unit mm).
        detections: Camera mode: ``detections[f][c]`` is a ``(D, 2)`` array of pixels.
        model: A subject model in place of the labeled first frame: ``names`` are then the
            model's markers, ``first_frame`` is ignored (NaN), and frame 0 is identified.
        unnamed_markers: Markers the take has that ``names`` leaves out (absent from the
            labeled frame): their points are in the frames, unnamed, from the start.
    """

    names: list[str]
    first_frame: np.ndarray
    rate: float
    points: list[np.ndarray] | None = None
    cameras: list[Camera] | None = None
    detections: list[list[np.ndarray]] | None = field(default=None, repr=False)
    model: SubjectModel | None = field(default=None, repr=False)
    unnamed_markers: int = 0

    def __post_init__(self) -> None:
        """Check and normalise what a notebook may hand in (``service.capture.checks``)."""
        if (self.points is None) == (self.detections is None):
            raise InputError("a capture has either 3D points or camera detections, not both or neither")
        if self.detections is not None and not self.cameras:
            raise InputError("camera detections need the cameras' calibration")
        if self.model is not None and self.points is None:
            raise InputError("labeling from a subject model needs 3D points (camera mode needs a labeled first frame)")
        self.names = checked_names(self.names)
        self.first_frame = checked_first_frame(self.first_frame, len(self.names))
        self.rate = checked_rate(self.rate)
        self.unnamed_markers = checked_count(self.unnamed_markers, "unnamed_markers")
        if self.points is not None:
            self.points = checked_frames(self.points, 3, "points")
            check_frame0_points(self.first_frame, self.points[0])
        elif self.unnamed_markers:
            raise InputError(f"unnamed_markers={self.unnamed_markers}: unnamed tracks are followed in 3D points only; "
                             "in camera mode every marker the detections show must be named in the first frame")
        else:
            self._check_cameras()

    def _check_cameras(self) -> None:
        cameras = list(self.cameras or [])
        if len(cameras) < 2 or not all(isinstance(camera, Camera) for camera in cameras):
            raise InputError(f"camera mode needs at least 2 calibrated cameras (Camera), got {len(cameras)}")
        names = [camera.name for camera in cameras]
        if len(set(names)) < len(names):  # outputs name the best view by camera name
            named_twice = sorted({name for name in names if names.count(name) > 1})
            raise InputError(f"camera names must be unique (outputs name views by them): {', '.join(map(repr, named_twice))} "
                             "given more than once")
        self.detections = checked_detections(self.detections, len(cameras))
        for c, camera in enumerate(cameras):
            off = first_off_sensor([frame[c] for frame in self.detections], camera.image_size)
            if off is not None:
                raise InputError(f"detections[{off[0]}] of camera {camera.name!r}: {off[2].tolist()} is "
                                 f"outside its {camera.image_size[0]}x{camera.image_size[1]} image")
            twice = first_duplicate([frame[c] for frame in self.detections])
            if twice is not None:
                raise InputError(f"detections[{twice[0]}] of camera {camera.name!r}: detections {twice[1]} and "
                                 f"{twice[2]} are the same pixel (each listed twice by the export?)")
        problem = frame0_problem(cameras, frame0_offsets(self.frame0_distances()))
        if problem is not None and problem[0]:  # one camera off is a warning (result_warnings)
            raise InputError(problem[1])

    @property
    def mode(self) -> str:
        return "points" if self.points is not None else "cameras"

    @property
    def n_frames(self) -> int:
        return len(self.points) if self.points is not None else len(self.camera_frames()[1])

    def frame0_distances(self) -> list[np.ndarray | None]:
        """Camera mode: per camera, the labeled markers' projections' distances to frame 0's
        detections (``service.capture.reprojection``)."""
        cameras, detections = self.camera_frames()
        return frame0_distances(cameras, np.asarray(self.first_frame, dtype=float), detections[0])

    def camera_frames(self) -> tuple[list[Camera], list[list[np.ndarray]]]:
        """Camera mode: the cameras and each frame's detections per camera.

        Raises:
            InputError: A capture of 3D points.
        """
        if self.cameras is None or self.detections is None:
            raise InputError("a capture of 3D points has no cameras")
        return self.cameras, self.detections
