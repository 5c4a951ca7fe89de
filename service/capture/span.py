"""The span of frames ``markerflow track --start S --end E`` labels."""

from __future__ import annotations

from service.errors import InputError


def frame_span(start: int, end: int | None, n_frames: int) -> int:
    """The end of the span ``start .. end - 1`` of ``n_frames`` (``n_frames`` when ``end`` is None).

    A window needs the start frame and at least one frame after it.

    Raises:
        InputError: A take of fewer than two frames, ``start`` outside the take, or ``end``
            not after ``start + 1`` or past its last frame.
    """
    if n_frames < 2:
        raise InputError(f"the take has {n_frames} frame{'s' * (n_frames != 1)}; labeling needs at least 2")
    stop = n_frames if end is None else end
    given = f"--start {start}" + (f" --end {end}" if end is not None else "")
    if not 0 <= start < n_frames or not start + 2 <= stop <= n_frames:
        raise InputError(
            f"{given}: frames are counted from 0 at the take's first, whatever its own numbering; "
            f"the take has {n_frames}, so 0 <= start <= {n_frames - 2} and start + 2 <= end <= {n_frames}"
        )
    return stop
