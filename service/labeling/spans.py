"""Sliding windows that overlap by one frame (Jiang Sec. II-E).

A window of W frames holds a template frame and W-1 new frames; its last frame is the
template of the next window.
"""

from __future__ import annotations

from service.errors import InputError


def window_spans(n_frames: int, window: int) -> list[tuple[int, int]]:
    """``(template, last)`` frame index of each window covering frames 0..n_frames-1.

    Raises:
        InputError: A window shorter than 2 frames.
    """
    if window < 2:
        raise InputError(f"window must be at least 2 frames (a template and one new frame), got {window}")
    step = window - 1
    return [(start, min(start + step, n_frames - 1)) for start in range(0, n_frames - 1, step)]
