"""What one finished window leaves behind: its labels, fills, certificate and marker state.

An outcome is everything needed both to assemble the final trajectories and to resume
labeling after it, so a job that persists each outcome as it finishes loses nothing when
its process dies. ``to_bytes``/``from_bytes`` round-trip it exactly (``.npz``, no pickle:
a stored job must not be able to run code when it is loaded).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, fields

import numpy as np

from formulations.markers.state import MarkerState
from service.labeling.stats import WindowStats

_OPTIONAL = ("views", "positions", "confidence", "carry", "trusted_mean", "trusted_var")  # stored only when present


class StaleOutcome(ValueError):
    """A stored outcome whose marker state lacks fields this version needs (stored by an
    older markerflow): its window cannot be resumed from, only relabeled."""


@dataclass(frozen=True)
class WindowOutcome:
    """One labeled window.

    Attributes:
        index: Window number, from 0.
        point_index: ``(M, N)`` index of the point each marker took in each new frame of
            the window (template excluded), -1 where occluded.
        filled: ``(M, N, 3)`` predicted position where occluded, NaN elsewhere.
        stats: Certificate and timings.
        state: Marker state at the window's last frame: the next window's template.
        views: ``per-camera`` association only: ``(M, N, C)`` detection each marker took
            in each camera (after the cross-camera check), -1 for none. ``point_index``
            is then ``(M, 0)``: the markers took detections, not points.
        positions: ``per-camera`` only: ``(M, N, 3)`` located positions, NaN where no
            camera saw the marker.
        confidence: ``(M, N)`` probability that each marker's label is right
            (``service.labeling.confidence``); None in outcomes stored before it existed.
        carry: ``(N,)`` each marker's confidence at its last label so far: what the next
            window's confidences are carried on from (``carried``); None as above.
        trusted_mean, trusted_var: ``(N, K)`` each marker's neighbour distance statistics
            when its label was last trusted (``confidence.lifted``); None as above.
        labeling: The digest of the capture it was labeled from (``capture.fingerprint``),
            so it resumes only its own take; None in outcomes stored before it existed.
    """

    index: int
    point_index: np.ndarray
    filled: np.ndarray
    stats: WindowStats
    state: MarkerState
    views: np.ndarray | None = None
    positions: np.ndarray | None = None
    confidence: np.ndarray | None = None
    carry: np.ndarray | None = None
    trusted_mean: np.ndarray | None = None
    trusted_var: np.ndarray | None = None
    labeling: str | None = None

    def to_bytes(self) -> bytes:
        arrays = {f"state.{f.name}": getattr(self.state, f.name) for f in fields(MarkerState)}
        arrays.update({name: getattr(self, name) for name in _OPTIONAL if getattr(self, name) is not None})
        header = json.dumps({"index": self.index, "stats": self.stats.to_dict(), "labeling": self.labeling})
        buffer = io.BytesIO()
        np.savez_compressed(
            buffer, header=np.array(header), point_index=self.point_index, filled=self.filled, **arrays
        )
        return buffer.getvalue()

    @classmethod
    def from_bytes(cls, data: bytes) -> WindowOutcome:
        with np.load(io.BytesIO(data), allow_pickle=False) as stored:
            header = json.loads(str(stored["header"]))
            missing = [f.name for f in fields(MarkerState) if f"state.{f.name}" not in stored.files]
            if missing:
                raise StaleOutcome(f"window {header['index']} was stored without marker state {', '.join(missing)}")
            state = MarkerState(**{f.name: stored[f"state.{f.name}"] for f in fields(MarkerState)})
            return cls(
                index=int(header["index"]), point_index=stored["point_index"], filled=stored["filled"],
                stats=WindowStats(**header["stats"]), state=state, labeling=header.get("labeling"),
                **{name: stored[name] for name in _OPTIONAL if name in stored.files},
            )


def take_confidence(frames: int, markers: int, outcomes: list[WindowOutcome]) -> np.ndarray:
    """``(frames, markers)``: 1 in the given first frame, each window's raw confidences in
    its new frames, NaN where no stored window says (not labeled yet, or stored without)."""
    confidence = np.full((frames, markers), np.nan)
    confidence[0] = 1.0
    for outcome in outcomes:
        if outcome.confidence is not None:
            confidence[outcome.stats.template + 1 : outcome.stats.last + 1] = outcome.confidence
    return confidence
