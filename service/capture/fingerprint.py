"""A digest of what a capture holds, so stored window outcomes are resumed only on their own take.

Window size, frame count and marker count are checked apart (``labeling.outcome_fit``); two
takes of one marker set and length pass those checks, and resuming one from the other's
outcomes gives labels built on another take's marker states without a word. The digest
covers the names, the labeled first frame, the rate and every point or detection, in order:
BLAKE2b over their bytes (``hashlib``), about 0.1 s for 50 MB of points.
"""

from __future__ import annotations

import json
from hashlib import blake2b

import numpy as np

from service.capture.capture import Capture


def capture_fingerprint(capture: Capture) -> str:
    """32 hex digits that differ between captures whose names, first frame, rate, points or
    detections differ (the camera calibration and a subject model are not covered)."""
    digest = blake2b(digest_size=16)
    digest.update(json.dumps([capture.names, float(capture.rate), capture.unnamed_markers]).encode())
    _add(digest, capture.first_frame)
    for frame in capture.points or []:
        _add(digest, frame)
    for views in capture.detections or []:
        for detections in views:
            _add(digest, detections)
    return digest.hexdigest()


def _add(digest: blake2b, values: np.ndarray) -> None:
    """The array's shape, then its values as float64 (a list and an array of the same numbers agree)."""
    array = np.ascontiguousarray(values, dtype=float)
    digest.update(np.asarray(array.shape, dtype=np.int64).tobytes())
    digest.update(array.tobytes())
