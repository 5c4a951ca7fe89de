"""A PNG of the fitted body projected into one camera over its keypoints or its images, for a few frames."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the file-only backend)
import numpy as np  # noqa: E402

from formulations.cameras.camera import Camera  # noqa: E402
from formulations.pose.body import BodyModel  # noqa: E402
from service.io.formats.replace_file import replacing  # noqa: E402

PANELS = 4


def write_overlay(path: Path, camera: Camera, model: BodyModel, positions: np.ndarray, title: str,
                  detections: np.ndarray | None = None, image: Callable[[int], np.ndarray] | None = None,
                  numbers: Sequence[int] | None = None) -> None:
    """``PANELS`` frames spread over the take: the model's segments ``positions`` ``(F, J, 3)`` as lines
    in ``camera``'s view, over its detections ``(F, 25, 3)`` as dots (confidence > 0) or its frame
    ``image(f)``; each panel titled by the frame's number in the input's file names (``numbers[f]``, else
    ``f``), so a take that starts at file 5 or skips a frame shows which file each panel is. Written
    beside ``path`` and renamed onto it whole (``replacing``): a Ctrl-C left a cut PNG."""
    frames = np.unique(np.linspace(0, len(positions) - 1, PANELS).round().astype(int))
    figure, axes = plt.subplots(1, len(frames), figsize=(3.2 * len(frames), 5.2), squeeze=False)
    width, height = camera.image_size  # each panel is cropped to the body, 60 px around it
    for axis, f in zip(axes[0], frames):
        pixels = camera.project(positions[f])
        for index, node in enumerate(model.nodes):
            if node.parent >= 0:
                axis.plot(*pixels[[node.parent, index]].T, color="tab:blue", linewidth=2)
        shown = pixels[np.isfinite(pixels).all(axis=1)]
        if detections is not None:
            seen = detections[f, :, 2] > 0
            axis.scatter(*detections[f, seen, :2].T, s=12, color="tab:red", zorder=3)
            shown = np.vstack([shown, detections[f, seen, :2]])
        if image is not None:
            axis.imshow(image(f), cmap="gray")
        low, high = np.maximum(shown.min(axis=0) - 60, 0), np.minimum(shown.max(axis=0) + 60, (width, height))
        number = numbers[f] if numbers is not None else f
        axis.set(xlim=(low[0], high[0]), ylim=(high[1], low[1]), title=f"frame {number}", aspect="equal")
        axis.set_xticks([])
        axis.set_yticks([])
    over = "keypoints (red)" if detections is not None else "images"
    figure.suptitle(f"{title}: fitted body (blue) over {camera.name}'s {over}")
    figure.tight_layout()
    try:
        with replacing(path, ".png") as temp:  # a refusal is one line naming path
            figure.savefig(temp, format="png", dpi=80)
    finally:
        plt.close(figure)
