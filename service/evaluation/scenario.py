"""A scenario: how the simulator degrades a labeled recording into labeler input."""

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from formulations.methods.formulation import Formulation
from service.capture.capture import LabelingOptions
from service.errors import InputError
from service.io.toml_file import read_toml

MODES = ("cloud", "cameras")
FIRST_FRAMES = ("labeled", "model")
ASSOCIATIONS = ("joint-3d", "per-camera")
# Keys one mode reads and the other ignores.
_MODE_KEYS = {
    "cloud": ("noise_mm", "ghosts_per_frame", "ghost_spread_mm", "drop_rate", "drop_burst_frames", "unnamed_markers",
              "second_pass", "mht_reading"),
    "cameras": ("calibration", "pixel_noise", "merge_radius_px", "clutter_per_camera", "occlusion_rate",
                "occlusion_burst_frames", "up_axis", "association"),
}
_OTHER_MODE = {"cloud": "cameras", "cameras": "cloud"}
_EXPECTED: dict[object, str] = {
    float: "a number", int: "an integer", str: "a string", dict: "a table", bool: "true or false",
}
_NON_NEGATIVE = ("noise_mm", "ghosts_per_frame", "ghost_spread_mm", "seed", "start_frame", "frames", "unnamed_markers")
# Upper bounds far past any real capture: beyond them a value means nothing physical, and the
# simulator's memory grows with the counts (points per frame) or its arithmetic overflows (noise).
_AT_MOST: dict[str, float] = {
    "noise_mm": 1000.0,  # a metre of noise per coordinate: no body left to label
    "ghosts_per_frame": 1000.0,  # stray points per frame; each one is stored and labeled
    "ghost_spread_mm": 100_000.0,  # 100 m from the body: past any capture volume
    "pixel_noise": 10_000.0,  # px: larger than any sensor
    "merge_radius_px": 10_000.0,  # px: larger than any sensor
    "clutter_per_camera": 1000.0,  # spurious detections per camera and frame; each one is stored
}


@dataclass(frozen=True)
class Scenario:
    """Settings of one simulated capture, as read from a scenario TOML file.

    ``configs/scenarios/README.md`` documents every key with its unit and range.

    Attributes:
        mode: ``"cloud"`` (unlabeled 3D points per frame) or ``"cameras"`` (2D detections
            per calibrated camera).
        noise_mm: Standard deviation of the isotropic Gaussian noise on every sample, mm.
        drop_rate: Long-run fraction of marker-samples deleted, in ``[0, 1)``.
        drop_burst_frames: Mean length of a run of deleted frames, >= 1.
        ghosts_per_frame: Poisson mean of spurious points per frame.
        ghost_spread_mm: Standard deviation of a ghost's Gaussian offset from the body, mm.
        window: Frames per labeling window, >= 2.
        seed: Seed of the numpy random generator; the simulation is a function of it.
        start_frame: First frame of the recording used.
        frames: Number of frames used; 0 means up to the end of the recording.
        formulation: Name of the labeling formulation. In TOML also a table
            ``[formulation]`` with ``name`` and the formulation's parameters.
        formulation_parameters: The parameters of that table (filled by ``from_dict``).
        calibration: Camera mode: calibration file (Pose2Sim TOML, caliscope TOML or our
            JSON); a relative path is taken from the scenario file's folder.
        pixel_noise: Camera mode: standard deviation of the detection noise, px.
        merge_radius_px: Camera mode: projections closer than this merge into one blob.
        occlusion_rate: Camera mode: long-run fraction of (camera, marker) samples hidden.
        occlusion_burst_frames: Camera mode: mean length of a hidden run, frames.
        clutter_per_camera: Camera mode: Poisson mean of spurious detections per camera.
        association: Camera mode: ``"joint-3d"`` (cross-camera 3D points labeled by the
            window LP) or ``"per-camera"`` (the window LP in each camera's image, then
            triangulation).
        up_axis: Camera mode: the recording's vertical axis (0, 1 or 2) for placing it.
        first_frame: ``"labeled"`` (the labeler gets the first frame's names and positions) or
            ``"model"`` (cloud mode: it gets a subject model, ``markerflow eval --model``, and
            no labeled frame; the truth only scores).
        second_pass: Cloud mode without a model: label again from the take's distance
            spreads and keep the labeling closer to the first frame's rigid pairs
            (``LabelingOptions.second_pass``).
        mht_reading: Cloud mode, where the frame-by-frame reading runs: read by ``mht`` too
            (``LabelingOptions.mht_reading``).
        unnamed_markers: Cloud mode: this many markers, drawn with the seed, keep their points
            but get no name, as `track --start` leaves the markers absent in its start frame;
            a named marker on one of their points took a ghost.
    """

    mode: str = "cloud"
    noise_mm: float = 1.0
    drop_rate: float = 0.1
    drop_burst_frames: float = 10.0
    ghosts_per_frame: float = 2.0
    ghost_spread_mm: float = 200.0
    window: int = 20
    seed: int = 0
    start_frame: int = 0
    frames: int = 0
    formulation: str = "lp-l1"
    formulation_parameters: dict = field(default_factory=dict)
    calibration: str = ""
    pixel_noise: float = 0.5
    merge_radius_px: float = 3.0
    occlusion_rate: float = 0.1
    occlusion_burst_frames: float = 15.0
    clutter_per_camera: float = 2.0
    association: str = "joint-3d"
    up_axis: int = 2
    first_frame: str = "labeled"
    second_pass: bool = True
    mht_reading: bool = False
    unnamed_markers: int = 0

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, _typed(f.name, getattr(self, f.name), f.type))
        self._check_ranges()

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Scenario":
        """Build a scenario from a key/value mapping; missing keys take their defaults.

        Raises:
            InputError: On an unknown key, or a value of the wrong type or out of range.
        """
        d = dict(d)
        known = [f.name for f in fields(cls) if f.name != "formulation_parameters"]
        for key in d:  # formulation_parameters is the [formulation] table's, not a key of its own
            if key not in known:
                raise InputError(f"unknown scenario key '{key}' (known keys: {', '.join(known)})")
        if isinstance(d.get("formulation"), dict):
            table = dict(d["formulation"])
            d["formulation"] = table.pop("name", "")
            d["formulation_parameters"] = table
        scenario = cls(**d)
        other = [key for key in d if key in _MODE_KEYS[_OTHER_MODE[scenario.mode]]]
        if other:  # a value that would change nothing: say so rather than ignore it
            raise InputError(f"scenario key '{other[0]}' applies to mode = \"{_OTHER_MODE[scenario.mode]}\"; "
                             f"this scenario's mode is \"{scenario.mode}\"")
        return scenario

    @classmethod
    def from_toml(cls, path: str | Path) -> "Scenario":
        """Read a scenario TOML file (top-level keys only).

        Raises:
            InputError: If the file cannot be read or parsed, or on any bad key or value.
        """
        data = read_toml(path)
        calibration = data.get("calibration")
        if isinstance(calibration, str) and calibration and not Path(calibration).is_absolute():
            data["calibration"] = str(Path(path).parent / calibration)
        return cls.from_dict(data)

    @property
    def formulation_table(self) -> dict[str, Any]:
        """The ``[formulation]`` table: the name and its parameters."""
        return {"name": self.formulation, **self.formulation_parameters}

    def labeling_options(self, formulation: str | dict | Formulation | None = None) -> LabelingOptions:
        """How to label this scenario's capture; ``formulation`` replaces the scenario's own."""
        return LabelingOptions(
            formulation=self.formulation_table if formulation is None else formulation, window=self.window,
            association=self.association, second_pass=self.second_pass, mht_reading=self.mht_reading,
        )

    def frame_span(self, n_frames: int) -> tuple[int, int]:
        """``(start, stop)`` of the recording's frames this scenario uses, both modes.

        Raises:
            InputError: A start past the end, a span past the end, or fewer than 2 frames
                (as ``track``: the labeled frame and at least one to label).
        """
        start = self.start_frame
        if start >= n_frames:
            raise InputError(f"scenario key 'start_frame' {start} is past the end ({n_frames} frames)")
        stop = start + self.frames if self.frames else n_frames
        if stop > n_frames:
            raise InputError(f"scenario key 'frames': start_frame + frames = {stop} exceeds the {n_frames} frames")
        if stop - start < 2:
            raise InputError(
                f"scenario keys 'start_frame' {start} and 'frames' {self.frames} leave {stop - start} frame; "
                "eval needs at least 2 frames"
            )
        return start, stop

    @property
    def deletion_transitions(self) -> tuple[float, float]:
        """Per-frame transition probabilities of the visible/deleted Markov chain.

        With ``r = drop_rate`` and ``b = drop_burst_frames``, a deleted run ends with
        probability ``p_leave = 1/b`` per frame, so runs are geometric with mean ``b``.
        The stationary deleted fraction ``p_enter / (p_enter + p_leave)`` equals ``r``
        when ``p_enter = r / (b (1 - r))``.

        Returns:
            ``(p_enter, p_leave)``: visible -> deleted and deleted -> visible.
        """
        b, r = self.drop_burst_frames, self.drop_rate
        return r / (b * (1.0 - r)), 1.0 / b

    def _require(self, key: str, ok: bool, condition: str) -> None:
        if not ok:
            got = getattr(self, key)
            raise InputError(f"scenario key '{key}' must be {condition}, got {got!r}")

    def _check_cameras(self) -> None:
        self._require("calibration", self.calibration.strip() != "", "the path of a calibration file")
        self._require("association", self.association in ASSOCIATIONS, f"one of {', '.join(ASSOCIATIONS)}")
        for key in ("pixel_noise", "merge_radius_px", "clutter_per_camera"):
            self._require(key, getattr(self, key) >= 0, ">= 0")
            self._require(key, getattr(self, key) <= _AT_MOST[key], f"<= {_AT_MOST[key]:g}")
        self._require("occlusion_rate", 0.0 <= self.occlusion_rate < 1.0, "in [0, 1)")
        self._require("occlusion_burst_frames", self.occlusion_burst_frames >= 1.0, ">= 1")
        self._require("up_axis", self.up_axis in (0, 1, 2), "0, 1 or 2")

    def _check_ranges(self) -> None:
        if self.mode not in MODES:
            known = ", ".join(MODES)
            raise InputError(f"scenario key 'mode' must be one of {known}, got '{self.mode}'")
        if self.mode == "cameras":
            self._check_cameras()
        for key in _NON_NEGATIVE:
            self._require(key, getattr(self, key) >= 0, ">= 0")
        for key in ("noise_mm", "ghosts_per_frame", "ghost_spread_mm"):
            self._require(key, getattr(self, key) <= _AT_MOST[key], f"<= {_AT_MOST[key]:g}")
        self._require("drop_rate", 0.0 <= self.drop_rate < 1.0, "in [0, 1)")
        self._require("drop_burst_frames", self.drop_burst_frames >= 1.0, ">= 1")
        self._require("window", self.window >= 2, ">= 2")
        self._require("formulation", self.formulation.strip() != "", "a non-empty name")
        self._require("first_frame", self.first_frame in FIRST_FRAMES, f"one of {', '.join(FIRST_FRAMES)}")
        if self.first_frame == "model":
            self._require("mode", self.mode == "cloud", "cloud when first_frame is model")
        if self.unnamed_markers:
            self._require("mode", self.mode == "cloud", "cloud when unnamed_markers is set")
        # p_enter is a probability: r / (b (1 - r)) <= 1, i.e. r <= b / (1 + b).
        if self.deletion_transitions[0] > 1.0:
            raise InputError(
                f"scenario key 'drop_rate' {self.drop_rate} is unreachable with "
                f"drop_burst_frames {self.drop_burst_frames}: need drop_rate <= b / (1 + b)"
            )


def _typed(key: str, value: Any, kind: object) -> Any:
    """Check ``value`` against the field's annotation ``kind``; ints widen to float."""
    # bool is an int subclass in Python, but `window = true` is a mistake, not 1.
    if kind is float and isinstance(value, (int, float)) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise InputError(f"scenario key '{key}' must be a finite number, got {value}")
        return float(value)
    if kind is int and isinstance(value, int) and not isinstance(value, bool):
        return value
    if kind is str and isinstance(value, str):
        return value
    if kind is dict and isinstance(value, dict):
        return value
    if kind is bool and isinstance(value, bool):
        return value
    expected = _EXPECTED[kind]
    raise InputError(f"scenario key '{key}' must be {expected}, got {value!r}")

