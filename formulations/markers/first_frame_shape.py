"""How far each of several labelings of one take bends its rigid pairs off the labeled first frame.

Two labelings of a take (``service.labeling.second_pass``) must be told apart without the
truth. Their own confidences cannot do it: each pass's confidence is conditional on the
spreads it was labeled with, so a pass started from wider spreads is more doubtful about the
same right labels (CMU 135_02 under the hard preset, seed 0: first pass 83.6 % right with
20.8 % of its labels doubtful, second 95.6 % right with 25.2 %). What both must respect is
the first frame, which the user labeled: a marker on a rigid segment keeps its distances to
its segment mates, and a label on the wrong point breaks them.

For labelings L_1 .. L_P (``(F, N, 3)``, NaN where a marker has no label), the pair spreads
v^p_mj of each (``take_spread``: robust to a tenth of wrong labels) give each pair's rigidity
r_mj = min_p v^p_mj, the pair as rigid as any labeling shows it: a labeling that is wrong over
most of the take cannot make a rigid pair look loose to the others. Marker m's partners J_m
are its ``partners`` neighbours of least r_mj. With d0_mj their distance in the first frame,
and U the (frame t, marker m, partner j in J_m) triples labeled together in any labeling,

    disagreement(L_p) = mean over U of  min(| ||L_p[t, m] - L_p[t, j]|| - d0_mj |, cap)
                                        where L_p labels both m and j at t, else cap,

in mm, lower is better. A pair one labeling leaves out where another labels it costs the cap,
as much as a wrong label: accuracy counts a marker left unlabeled beside its point as wrong,
and a labeling judged only on what it labeled wins by labeling less (so it did once:
nn-hungarian on HDM05 at 4 mm noise, a 96.5 % pass kept over a 99.7 % one). The cap keeps one far wrong label from
outweighing many near ones.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.take_spread import take_spread

Array = NDArray[np.float64]

PARTNERS = 3  # a foot's or a head's plate: three mates fix a marker's place on its segment
CAP_MM = 50.0  # about a marker spacing: beyond it a label is wrong, by how much does not matter


def first_frame_disagreement(
    labelings: list[Array], first: Array, neighbours: NDArray[np.int64], partners: int = PARTNERS, cap_mm: float = CAP_MM,
) -> Array:
    """``(P,)`` each labeling's disagreement with the first frame (module doc), mm; all NaN when
    no labeling has a partner pair labeled together in any frame.

    Args:
        labelings: ``(F, N, 3)`` labeled positions of each labeling, NaN where unlabeled.
        first: ``(N, 3)`` the labeled first frame (NaN for a marker it lacks).
        neighbours: ``(N, K)`` each marker's neighbours (``MarkerState.neighbours``).
    """
    return disagreement(*pair_offsets(labelings, first, neighbours, partners, cap_mm))


def disagreement(capped: Array, judged: NDArray[np.bool_]) -> Array:
    """``(P,)`` each labeling's mean capped offset over the judged triples (``pair_offsets``);
    all NaN when no triple is judged."""
    if not judged.any():
        return np.full(len(capped), np.nan)
    return np.array([each[judged].mean() for each in capped])


def pair_offsets(
    labelings: list[Array], first: Array, neighbours: NDArray[np.int64], partners: int = PARTNERS, cap_mm: float = CAP_MM,
) -> tuple[Array, NDArray[np.bool_]]:
    """``(P, F, N, R)`` each labeling's offset of each marker's R rigid partners off the first
    frame, ``min(| ||L_p[t, m] - L_p[t, j]|| - d0_mj |, cap)``, the cap where it does not label
    both (module doc); and ``(F, N, R)`` the triples some labeling labels together (U)."""
    mates = _rigid_mates(labelings, neighbours, partners)
    rest = np.linalg.norm(first[:, None] - first[mates], axis=2)
    off = np.stack([np.abs(np.linalg.norm(positions[:, :, None] - positions[:, mates], axis=3) - rest)
                    for positions in labelings])  # NaN where a pair is not labeled together
    capped: Array = np.where(np.isfinite(off), np.minimum(off, cap_mm), cap_mm)
    return capped, np.isfinite(off).any(axis=0)


def _rigid_mates(labelings: list[Array], neighbours: NDArray[np.int64], partners: int) -> NDArray[np.int64]:
    """``(N, partners)`` each marker's neighbours of least spread r_mj in any labeling (module doc)."""
    rigidity = np.fmin.reduce([take_spread(positions, neighbours) for positions in labelings])
    order = np.argsort(np.where(np.isfinite(rigidity), rigidity, np.inf), axis=1)[:, :partners]
    mates: NDArray[np.int64] = np.take_along_axis(neighbours, order, axis=1)
    return mates
