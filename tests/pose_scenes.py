"""Synthetic scenes for the pose tests and bench: a walking body driven by simple joint-angle curves,
seen as keypoints or as rendered silhouettes (with sensor noise and background clutter)."""

from __future__ import annotations

import numpy as np

from formulations.cameras.camera import Camera
from formulations.pose.body import BodyModel
from formulations.pose.image_maps import edge_proximity, foreground_mask
from formulations.pose.keypoints import BODY_25B
from formulations.pose.kinematics import forward_kinematics
from formulations.pose.render import render_silhouette

# Where Pose2Sim's demo participant stands in its calibration's world (m, z up).
POSE2SIM_STANCE = np.array([-1.4, 0.0, 0.95])


def set_angle(model: BodyModel, configurations: np.ndarray, joint: str, axis: str, values: np.ndarray) -> None:
    node = model.nodes[model.index(joint)]
    configurations[:, model.columns[model.index(joint)] + node.axes.index(axis)] = values


def walking(model: BodyModel, frames: int, rate: float = 60.0, stance: np.ndarray = POSE2SIM_STANCE) -> np.ndarray:
    """``(frames, D)`` a body stepping in place while turning slowly, arms swinging (1 Hz gait)."""
    phase = 2 * np.pi * np.arange(frames) / rate
    X = np.zeros((frames, model.dof))
    X[:, :3] = stance + np.column_stack([0.1 * np.sin(0.5 * phase), 0.05 * np.cos(0.5 * phase), 0.01 * np.sin(2 * phase)])
    X[:, 3] = 0.3 + 0.2 * np.sin(0.25 * phase)  # heading
    for side, sign in (("R", 1.0), ("L", -1.0)):
        set_angle(model, X, f"{side}Hip", "y", -0.35 * sign * np.sin(phase))
        set_angle(model, X, f"{side}Knee", "y", 0.45 + 0.35 * sign * np.sin(phase + 1.0))
        set_angle(model, X, f"{side}Shoulder", "y", 0.3 * sign * np.sin(phase))
        set_angle(model, X, f"{side}Elbow", "y", -0.6 - 0.3 * sign * np.sin(phase))
    return model.clip(X)


def keypoints(model: BodyModel, X: np.ndarray, cameras: list[Camera], noise_px: float, rng: np.random.Generator) -> np.ndarray:
    """``(F, C, 25, 3)`` the model's joints named like BODY_25B keypoints, projected with noise, confidence 0.9."""
    positions = forward_kinematics(model, X).positions
    detections = np.zeros((len(X), len(cameras), len(BODY_25B), 3))
    for n, name in enumerate(model.names):
        if name in BODY_25B:
            for c, camera in enumerate(cameras):
                pixels = camera.project(np.ascontiguousarray(positions[:, n]))
                detections[:, c, BODY_25B.index(name), :2] = pixels + rng.normal(0, noise_px, (len(X), 2))
                detections[:, c, BODY_25B.index(name), 2] = 0.9
    return detections


def background(camera: Camera, rng: np.random.Generator, clutter: int = 40) -> np.ndarray:
    """A grey 8-bit image with random rectangles and lines: edges that are not the body."""
    width, height = camera.image_size
    image = np.full((height, width), 90, np.uint8)
    for _ in range(clutter):
        x, y = rng.integers(0, width), rng.integers(0, height)
        w, h = rng.integers(20, 200, size=2)
        image[y:y + h, x:x + w] = rng.integers(40, 160)
    return image


def silhouette_maps(model: BodyModel, configuration: np.ndarray, cameras: list[Camera], backgrounds: list[np.ndarray],
                    rng: np.random.Generator, noise: float = 6.0) -> tuple[np.ndarray, np.ndarray]:
    """``(C, H, W)`` edge proximity and foreground of the body rendered over each background with sensor noise."""
    edges, foreground = [], []
    for camera, back in zip(cameras, backgrounds):
        image = render_silhouette(model, configuration, camera, back)
        noisy = np.clip(image + rng.normal(0, noise, image.shape), 0, 255).astype(np.uint8)
        edges.append(edge_proximity(noisy))
        foreground.append(foreground_mask(noisy, back))
    return np.stack(edges), np.stack(foreground)
