"""Checks of a capture built in Python, the library's counterpart of the capture document's schema.

A capture document is checked field by field by pydantic (``service.capture.document``); a
``Capture`` built in a notebook skips that, and a wrong shape or a NaN used to surface eleven
frames deep as a numpy or scipy error (or a ckdtree ``'x' must be finite``). These checks run
when the capture is made, say in one line what is wrong and where, and hand back the frames
as float arrays, so a list of lists is as good as an array.
"""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from service.errors import InputError

MIN_RATE, MAX_RATE = 1e-3, 1e5  # Hz: a frame per 1,000 s to 100 kHz (see CaptureDocument.rate)
MAX_COORDINATE = 1e9  # mm or px: sums of squares of larger values overflow inside the geometry


def checked_rate(rate: object) -> float:
    """``rate`` as a float, in ``[MIN_RATE, MAX_RATE]`` Hz."""
    if isinstance(rate, bool) or not isinstance(rate, Real) or not np.isfinite(float(rate)):
        raise InputError(f"rate must be a finite number of frames per second, got {rate!r}")
    if not MIN_RATE <= float(rate) <= MAX_RATE:
        raise InputError(f"rate must be between {MIN_RATE:g} and {MAX_RATE:g} frames per second, got {rate!r}")
    return float(rate)


def checked_count(value: object, what: str, least: int = 0) -> int:
    """``value`` as an int of at least ``least``; ``what`` names it in the message."""
    if isinstance(value, bool) or not isinstance(value, Integral) or int(value) < least:
        raise InputError(f"{what} must be a whole number of at least {least}, got {value!r}")
    return int(value)


def checked_names(names: object) -> list[str]:
    """Marker names as a list of distinct, non-blank strings."""
    if isinstance(names, str) or not isinstance(names, (list, tuple)):
        raise InputError(f"names must be a list of marker names, got {type(names).__name__}")
    seen: set[str] = set()
    for i, name in enumerate(names):
        if not isinstance(name, str) or not name.strip():
            raise InputError(f"names[{i}]: a marker name must be a non-blank string, got {name!r}")
        if name in seen:
            raise InputError(f"names[{i}]: marker name {name!r} appears twice")
        seen.add(name)
    return list(names)


def checked_first_frame(first_frame: object, n_markers: int) -> np.ndarray:
    """``(n_markers, 3)`` float positions (NaN allowed: a marker the labeled frame lacks)."""
    array = _float_array(first_frame, "first_frame")
    if array.shape != (n_markers, 3):
        raise InputError(f"first_frame must be ({n_markers}, 3), one (x, y, z) per marker name; got shape {array.shape}")
    bad = np.flatnonzero((np.abs(array) > MAX_COORDINATE).any(axis=1))  # NaN passes: a marker left unlabeled
    if len(bad):
        raise InputError(f"first_frame[{bad[0]}]: {array[bad[0]].tolist()} is not a finite coordinate within "
                         f"{MAX_COORDINATE:g} (NaN for a marker the labeled frame lacks)")
    return array


def checked_frames(frames: object, columns: int, what: str, limit: float = MAX_COORDINATE) -> list[np.ndarray]:
    """Each frame as a ``(P, columns)`` float array of finite values, at least 2 frames."""
    if isinstance(frames, np.ndarray) and frames.ndim == 3:
        frames = list(frames)
    if not isinstance(frames, (list, tuple)):
        raise InputError(f"{what} must be a list with one array per frame, got {type(frames).__name__}")
    if len(frames) < 2:
        raise InputError(f"a capture needs at least 2 frames (the labeled frame and one more), got {len(frames)}")
    return [checked_points(frame, columns, f"{what}[{f}]", limit) for f, frame in enumerate(frames)]


def checked_points(points: object, columns: int, where: str, limit: float = MAX_COORDINATE) -> np.ndarray:
    """One frame's ``(P, columns)`` points; an empty frame may be ``[]``."""
    array = _float_array(points, where)
    if array.size == 0:
        return array.reshape(0, columns)
    if array.ndim != 2 or array.shape[1] != columns:
        raise InputError(f"{where}: points must be ({'P' if columns == 3 else 'D'}, {columns}), got shape {array.shape}")
    bad = np.flatnonzero(~(np.abs(array) <= limit).all(axis=1))
    if len(bad):
        raise InputError(f"{where}[{bad[0]}]: {array[bad[0]].tolist()} is not a finite coordinate within "
                         f"{limit:g} (leave a missing point out of its frame instead of NaN)")
    return array


def checked_detections(detections: object, n_cameras: int) -> list[list[np.ndarray]]:
    """``detections[f][c]`` as ``(D, 2)`` pixel arrays, one per camera in every frame."""
    if not isinstance(detections, (list, tuple)):
        raise InputError(f"detections must be a list per frame of one (D, 2) array per camera, "
                         f"got {type(detections).__name__}")
    if len(detections) < 2:
        raise InputError(f"a capture needs at least 2 frames (the labeled frame and one more), got {len(detections)}")
    checked = []
    for f, frame in enumerate(detections):
        if not isinstance(frame, (list, tuple)) or len(frame) != n_cameras:
            raise InputError(f"detections[{f}] must hold one (D, 2) array per camera ({n_cameras} cameras), "
                             f"got {len(frame) if isinstance(frame, (list, tuple)) else type(frame).__name__}")
        checked.append([checked_points(pixels, 2, f"detections[{f}][{c}]") for c, pixels in enumerate(frame)])
    return checked


def first_off_sensor(frames: list, image_size: tuple[int, int]) -> tuple[int, int, np.ndarray] | None:
    """``(frame, detection, pixel)`` of one camera's first detection off its sensor
    (``[-0.5, size - 0.5]`` per axis, as ``Camera.in_image``) over its ``frames`` of
    ``(D, 2)`` pixels, or None; all frames in one array test."""
    counts = [len(frame) for frame in frames]
    if not sum(counts):
        return None
    pixels = np.concatenate([np.asarray(frame, dtype=float).reshape(-1, 2) for frame in frames])
    upper = np.asarray(image_size, dtype=float) - 0.5
    outside = np.flatnonzero(((pixels < -0.5) | (pixels > upper)).any(axis=1))
    if not len(outside):
        return None
    first = int(outside[0])
    f = int(np.searchsorted(np.cumsum(counts), first, side="right"))
    return f, first - sum(counts[:f]), pixels[first]


def first_duplicate(frames: list) -> tuple[int, int, int] | None:
    """``(frame, first, second)`` of one camera's first frame holding one pixel twice over its
    ``frames`` of ``(D, 2)`` pixels, or None. An export that lists each centroid twice made
    ``per-camera`` fuse two markers onto one position; no detector finds one blob twice to
    the last bit, so it is refused rather than guessed at. All frames in one sort."""
    counts = np.array([len(frame) for frame in frames])
    if counts.sum() < 2:
        return None
    pixels = np.concatenate([np.asarray(frame, dtype=float).reshape(-1, 2) for frame in frames])
    frame_of = np.repeat(np.arange(len(frames)), counts)
    order = np.lexsort((pixels[:, 1], pixels[:, 0], frame_of))
    same = (np.diff(frame_of[order]) == 0) & (np.diff(pixels[order], axis=0) == 0).all(axis=1)
    if not same.any():
        return None
    at = np.flatnonzero(same)
    k = at[np.argmin(frame_of[order][at])]  # the earliest frame's pair
    f = int(frame_of[order][k])
    first, second = sorted(int(i) - int(counts[:f].sum()) for i in order[k : k + 2])
    return f, first, second


def _float_array(value: object, where: str) -> np.ndarray:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: not an array of numbers (ragged rows or a non-number)") from None
