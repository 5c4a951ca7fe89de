"""Tile a labeled take along its frames to a longer one, for measuring memory against take length.

Copies alternate forward and time-reversed (each reversed copy drops the frame it shares with
the copy before), so no marker jumps where two copies meet: the labeler sees one long take of
the same motion, and a memory figure measured on it grows with length, not with new difficulty.

    python bench/tile_take.py 135_02.c3d 10000 out/135_02_x10000.c3d
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories


def tiled(positions: np.ndarray, frames: int) -> np.ndarray:
    """``positions`` ``(F, M, 3)`` continued to ``frames`` frames by forward and reversed copies."""
    pieces, have, forward = [positions], len(positions), False
    while have < frames:
        piece = positions[::-1][1:] if not forward else positions[1:]
        pieces.append(piece)
        have += len(piece)
        forward = not forward
    return np.concatenate(pieces)[:frames]


def main(source: str, frames: int, output: str) -> None:
    recording = read_labeled(source)
    positions = tiled(recording.positions, frames)
    occluded = np.isnan(positions).any(axis=2)
    write_labeled(Path(output), LabeledTrajectories(list(recording.names), positions, occluded, recording.rate))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
