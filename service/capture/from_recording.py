"""A labeled recording as a capture to relabel: frame 0 labeled, every frame's points unnamed.

``markerflow track`` and the HTTP upload of a C3D/TRC both label a recording this way, so
they give the same answer for the same file.
"""

from __future__ import annotations

import numpy as np

from service.capture.capture import Capture
from service.io.recording import Recording


def capture_from_recording(recording: Recording, shuffle: bool = True, seed: int = 0) -> Capture:
    """Each frame's present points without their labels; the recording's frame 0 labeled.

    Missing samples (NaN, or (0, 0, 0)) are dropped; the fixed seed makes the shuffle,
    and so the labeling, a function of the file alone.
    """
    rng = np.random.default_rng(seed)
    present = ~recording.missing()
    frames = []
    for f in range(recording.n_frames):
        points = recording.positions[f][present[f]]
        frames.append(points[rng.permutation(len(points))] if shuffle else points)
    return Capture(list(recording.names), recording.positions[0], recording.rate, points=frames)
