"""The per-frame loop over keypoint input: participant, body, start, then one annealed search per frame.

The body is the default human (``formulations.pose.human``) with segment lengths fitted to the
participant (median triangulated keypoint distances over the take, and the shoulders' drop below
the neck keypoint, the nose's and the foot's geometry from triangles of them, ``fit_proportions``),
a calibration of the subject done once before tracking, so the fit keeps one length per bone; or a
body built from a subject model. The first frame is searched from a standing pose placed on the
triangulated hips and neck, with three times the layers.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from formulations.cameras.camera import Camera
from formulations.cameras.rig import Rig
from formulations.errors import FormulationError
from formulations.pose.apf import AnnealingSchedule
from formulations.pose.body import BodyModel
from formulations.pose.human import human_model
from formulations.pose.initial import fit_proportions, standing_start
from formulations.pose.keypoints import BODY_25B, KeypointMeasurement, KeypointPairs
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.refine import refine as polish
from formulations.pose.tracker import PoseTracker, dispersion
from service.errors import InputError
from service.pose.participant import triangulate

# The first frame is searched from a standing pose with three times the layers. A wider first dispersion
# was tried (2-6 times) and fitted synthetic keypoints worse: 300 particles spread thinner over 33 DOF.
FIRST_FRAME_LAYERS = 3
# The refinement's Cauchy scale: OpenPose's keypoint noise where cameras agree (Pose2Sim's triangulation
# reprojects onto the cameras it keeps within about 5-8 px), so a camera that puts a keypoint tens of
# pixels away is discounted instead of averaged in. On the demo's single-person trial: 15 px (the APF's) gives
# 14.5 px median reprojection error, 5 px 13.6 px.
REFINE_SIGMA_PX = 5.0
STEP_METRES = 0.02  # the root's first-layer dispersion per frame (60 Hz walking moves about 1-2 cm)
Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class PoseFit:
    """The fitted body: its joints' names and positions ``(F, J, 3)`` (calibration units), which frames
    had keypoints, the reprojection errors ``(F, C, 25)`` (px, NaN where no detection) and seconds per frame."""

    model: BodyModel
    names: list[str]
    positions: np.ndarray
    observed: np.ndarray
    reprojection: np.ndarray
    seconds_per_frame: float


def fit_keypoints(cameras: list[Camera], detections: np.ndarray, metres_per_unit: float, model: BodyModel | None,
                  schedule: AnnealingSchedule, seed: int = 0, progress: Progress | None = None,
                  refine: bool = True) -> PoseFit:
    """Track the participant's ``(F, C, 25, 3)`` keypoints (``participant.choose_participant``).

    The F frames are searched one after another however far apart their numbers are: a gap in the
    input's numbering (a frame no camera has a file for) is crossed as a frame nobody was seen in
    is, by searching from the last estimate, since the default search has no motion model to
    stretch over it (``PoseTracker(damping=...)`` would need the gap's length, a change to the
    tracker). The caller keeps the frames' numbers for the output."""
    rig = Rig.of(cameras)
    points = np.stack([triangulate(rig, frame) for frame in detections])  # (F, 25, 3)
    named = {name: points[:, k] for k, name in enumerate(BODY_25B)}
    if model is None:
        model = human_model(fit_proportions(named, metres_per_unit)).scaled(1.0 / metres_per_unit)
    try:
        pairs = KeypointPairs.of(model)
        first = next(f for f in range(len(points)) if np.isfinite(points[f, [12, 11, 17]]).all())
        start = standing_start(model, *(named[n][first] for n in ("RHip", "LHip", "Neck")))
    except StopIteration:
        raise InputError("no frame where two cameras see the participant's hips and neck: cannot start") from None
    except FormulationError as error:
        raise InputError(str(error)) from None
    tracker = PoseTracker(model, start, dispersion(model, STEP_METRES / metres_per_unit), schedule, seed=seed)
    positions = np.empty((len(detections), len(model.nodes), 3))
    observed = np.zeros(len(detections), dtype=bool)
    began = time.perf_counter()
    for f in range(len(detections)):
        measurement = KeypointMeasurement(rig, pairs, detections[f])
        # Frames before the first one seen keep the start pose (unobserved); searching starts there.
        searched = f >= first
        estimate, observed[f] = tracker.step([measurement] if searched else [],
                                             layers=schedule.layers * FIRST_FRAME_LAYERS if f == first else None)
        if refine and observed[f]:
            estimate = polish(model, replace(measurement, sigma=REFINE_SIGMA_PX), estimate)
            tracker.correct(estimate)  # the next frame's search starts from the refined pose
        positions[f] = forward_kinematics(model, estimate[None]).positions[0]
        if progress is not None:
            progress(f + 1, len(detections))
    seconds = (time.perf_counter() - began) / len(detections)
    return PoseFit(model, model.names, positions, observed, _reprojection(rig, model, positions, detections), seconds)


def _reprojection(rig: Rig, model: BodyModel, positions: np.ndarray, detections: np.ndarray) -> np.ndarray:
    pairs = KeypointPairs.of(model)
    errors = np.full(detections.shape[:3], np.nan)
    joints = positions[:, pairs.nodes]
    for c, camera in enumerate(rig.cameras):
        pixels = camera.project(joints.reshape(-1, 3)).reshape(len(positions), -1, 2)
        distance = np.linalg.norm(pixels - detections[:, c, pairs.keypoints, :2], axis=2)
        errors[:, c, pairs.keypoints] = np.where(detections[:, c, pairs.keypoints, 2] > 0, distance, np.nan)
    return errors
