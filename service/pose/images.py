"""Per-camera image folders: the edge and foreground maps of each frame, and the fit by edges + foreground.

INPUT holds one folder per camera (named so ``openpose.match_cameras`` finds its calibration,
e.g. ``cam01``), each with one image per frame (.png, .jpg, .jpeg, .bmp, sorted by name). The
foreground is found against a reference image with no one in it (Fig. 2c): ``background.*`` in
the camera's folder; without one, the per-pixel median of up to ``BACKGROUND_FRAMES`` frames
spread over the take stands in, right where the subject moves about, wrong where they stand
still for most of the take. The body's starting pose assumes the calibration's world z axis
points up (Pose2Sim's and Qualisys's do).
The search starts from a standing body at the triangulated centroid of the foreground masks,
trying ``HEADINGS`` headings on the first frame and keeping the best.
"""

from __future__ import annotations

import time
from pathlib import Path

import cv2
import numpy as np

from formulations.cameras.camera import Camera
from formulations.cameras.rig import Rig
from formulations.pose.apf import AnnealingSchedule
from formulations.pose.body import TRANSLATION_DOF, BodyModel
from formulations.pose.image_maps import edge_proximity, foreground_mask
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.silhouette import SilhouetteMeasurement
from formulations.pose.tracker import PoseTracker, dispersion
from service.errors import InputError
from service.pose.openpose import numbered_paths
from service.pose.run import FIRST_FRAME_LAYERS, STEP_METRES, PoseFit, Progress

SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp"}
BACKGROUND = "background"
BACKGROUND_FRAMES = 25
HEADINGS = 4


def _images(folder: Path) -> dict[int, Path]:
    """The folder's frames by the number in their names (``numbered_paths``): sorted names put
    ``f10.png`` before ``f9.png``."""
    return numbered_paths(sorted(f for f in folder.iterdir() if f.suffix.lower() in SUFFIXES and f.stem != BACKGROUND),
                          folder)


def image_folders(input: Path) -> tuple[list[int], dict[str, list[Path]]]:
    """The frame numbers in the images' names, and each subfolder of ``input`` that holds images
    with its frames in the order of those numbers; every camera must number the same frames
    (paired by position, a camera starting later would be fitted out of step)."""
    folders = {p.name: _images(p) for p in sorted(input.iterdir()) if p.is_dir()} if input.is_dir() else {}
    folders = {name: files for name, files in folders.items() if files}
    if len({tuple(sorted(files)) for files in folders.values()}) > 1:
        listed = ", ".join(f"{name} {min(files)}-{max(files)} ({len(files)})" for name, files in folders.items())
        raise InputError(f"{input}: the cameras' images are numbered differently: {listed}")
    numbers = sorted(next(iter(folders.values()))) if folders else []
    return numbers, {name: [files[n] for n in numbers] for name, files in folders.items()}


def read_frame(path: Path, camera: Camera) -> np.ndarray:
    """One 8-bit grey frame of ``camera``'s size."""
    image: np.ndarray | None = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise InputError(f"{path}: cannot read the image")
    if (image.shape[1], image.shape[0]) != camera.image_size:
        raise InputError(f"{path}: image is {image.shape[1]}x{image.shape[0]}, camera {camera.name} is "
                         f"{camera.image_size[0]}x{camera.image_size[1]}")
    return image


def _background(files: list[Path], camera: Camera) -> np.ndarray:
    """The camera folder's ``background.*``, else the median of frames spread over the take."""
    given = [f for f in files[0].parent.iterdir() if f.stem == BACKGROUND and f.suffix.lower() in SUFFIXES]
    if given:
        return read_frame(given[0], camera)
    chosen = np.linspace(0, len(files) - 1, min(BACKGROUND_FRAMES, len(files))).astype(int)
    median: np.ndarray = np.median([read_frame(files[i], camera) for i in chosen], axis=0).astype(np.uint8)
    return median


def fit_images(cameras: list[Camera], files: list[list[Path]], model: BodyModel, metres_per_unit: float,
               schedule: AnnealingSchedule, seed: int = 0, progress: Progress | None = None) -> PoseFit:
    """Track the body through ``files[c][f]`` by edges + foreground (``formulations.pose.silhouette``)."""
    rig, frames = Rig.of(cameras), len(files[0])
    spread = dispersion(model, STEP_METRES / metres_per_unit)
    backgrounds = [_background(f, c) for f, c in zip(files, cameras)]
    positions = np.empty((frames, len(model.nodes), 3))
    observed = np.zeros(frames, dtype=bool)
    tracker: PoseTracker | None = None
    began = time.perf_counter()
    for f in range(frames):
        images = [read_frame(files[c][f], camera) for c, camera in enumerate(cameras)]
        measurement = SilhouetteMeasurement(rig, model, np.stack([edge_proximity(i) for i in images]),
                                            np.stack([foreground_mask(i, b) for i, b in zip(images, backgrounds)]))
        if tracker is None and not measurement.empty:
            start = _first_pose(rig, model, measurement, spread, schedule, seed)
            tracker = PoseTracker(model, start, spread, schedule, seed=seed)
        if tracker is None:
            positions[f] = np.nan
        else:
            estimate, observed[f] = tracker.step([measurement])
            positions[f] = forward_kinematics(model, estimate[None]).positions[0]
        if progress is not None:
            progress(f + 1, frames)
    if tracker is None:
        raise InputError("no frame shows anything in front of the background: nothing to fit")
    seconds = (time.perf_counter() - began) / frames
    return PoseFit(model, model.names, positions, observed, np.full((frames, len(cameras), 25), np.nan), seconds)


def _first_pose(rig: Rig, model: BodyModel, measurement: SilhouetteMeasurement, spread: np.ndarray,
                schedule: AnnealingSchedule, seed: int) -> np.ndarray:
    """The best of ``HEADINGS`` searches from a standing body whose pelvis is at the foreground's centroid."""
    centroids = np.full((1, len(rig), 2), np.nan)
    for c, mask in enumerate(measurement.foreground):
        rows, columns = np.nonzero(mask)
        if len(rows):
            centroids[0, c] = (columns.mean(), rows.mean())
    centre = rig.triangulate(rig.undistort(centroids))[0]
    if not np.isfinite(centre).all():
        raise InputError("the first frame with foreground shows it in fewer than two cameras: cannot start")
    first = AnnealingSchedule(schedule.particles, schedule.layers * FIRST_FRAME_LAYERS, schedule.survival, schedule.final_spread)
    best, lowest = np.zeros(model.dof), np.inf
    for heading in np.arange(HEADINGS) * 2 * np.pi / HEADINGS:
        start = np.zeros(model.dof)
        start[:TRANSLATION_DOF] = centre
        start[TRANSLATION_DOF] = heading
        searcher = PoseTracker(model, start, spread, schedule, seed=seed)
        result = searcher.search([measurement], start, first, spread * 3.0)
        energy = float(measurement.energy(forward_kinematics(model, result.estimate[None]))[0])
        if energy < lowest:
            best, lowest = result.estimate, energy
    return best
