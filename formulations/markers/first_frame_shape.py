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
r_mj = min_p v^p_mj over the labelings p that label the pair together in at least a fifth
(``SUPPORT_SHARE``) of the frames n^p_mj the most complete one does: the pair as rigid as
any labeling shows it, so one wrong over most of the take cannot make a rigid pair look loose
to the others. The support keeps a labeling that labels a marker only in a few still frames
from making it rigid with anything (CMU 135_02, hard preset, seed 1: the frame-by-frame
reading labeled LFIN in its first 22 frames, standing still, and so made the finger rigid
with the hip, and the right labels of 58-121 lost to a wrist marker holding its point; with
the support its partners are the wrist, forearm and elbow markers LWRA, LFRM and LELB, and
that run 95.58 -> 96.14 %; on the accuracy matrix, seeds 0-2, the tuning half is level and
the validation half within 0.011 points either way: docs/track.md). Marker m's partners J_m
are its ``partners`` neighbours of least r_mj. With d_mj their rest length (``rest_lengths``: the
first frame's distance, or the median of the distances the labelings agree on where the first
frame is an outlier of those),
and U the (frame t, marker m, partner j in J_m) triples labeled together in any labeling,

    o_p(t, m, j) = | ||L_p[t, m] - L_p[t, j]|| - d_mj |
    disagreement(L_p) = mean over U of  o_p(t, m, j)   where L_p labels both m and j at t
                                                       and o_p <= tol_mj,
                                        cap             else,
    tol_mj = max(5 sqrt(r_mj), n_m / 2),

in mm, lower is better, n_m being m's nearest-neighbour distance in the first frame. An
offset beyond tol_mj is a wrong label, and costs what a leave-out does: kept as it was (up
to the cap), a marker put on a close neighbour's point (a wrist's two styloid markers, their
partners at the elbow) bent its pairs by less than the cap the other labeling paid for
leaving the absent marker out (03_rolling at 2 mm noise, seed 0: the frame-by-frame
reading's LL_RSP and LL_USP). The tolerance is the shape breaks' (``shape_breaks``): five
spreads of a pair that rigid, or half a marker spacing. A pair one labeling leaves out where
another labels it costs the cap,
as much as a wrong label: accuracy counts a marker left unlabeled beside its point as wrong,
and a labeling judged only on what it labeled wins by labeling less (so it did once:
nn-hungarian on HDM05 at 4 mm noise, a 96.5 % pass kept over a 99.7 % one). The cap keeps one far wrong label from
outweighing many near ones.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.rest_lengths import rest_lengths
from formulations.markers.shape_breaks import NEAREST_SHARE, SPREADS
from formulations.markers.take_spread import take_spread

Array = NDArray[np.float64]

PARTNERS = 3  # a foot's or a head's plate: three mates fix a marker's place on its segment
CAP_MM = 50.0  # about a marker spacing: beyond it a label is wrong, by how much does not matter
SUPPORT_SHARE = 0.2  # of the most frames any labeling labels a pair together in (module doc)


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
    frame, ``| ||L_p[t, m] - L_p[t, j]|| - d_mj |``, the cap where it does not label both or
    the offset passes the tolerance (module doc); and ``(F, N, R)`` the triples some labeling
    labels together (U)."""
    return mate_offsets(labelings, first, *rigid_mates(labelings, neighbours, partners), cap_mm)


def mate_offsets(
    labelings: list[Array], first: Array, mates: NDArray[np.int64], spread: Array, cap_mm: float = CAP_MM,
) -> tuple[Array, NDArray[np.bool_]]:
    """``pair_offsets`` for the ``mates`` and their ``spread`` (``rigid_mates``) found already."""
    gaps = np.linalg.norm(first[:, None] - first[None], axis=2)
    np.fill_diagonal(gaps, np.inf)
    tolerance = np.fmax(SPREADS * np.sqrt(spread), NEAREST_SHARE * np.nanmin(gaps, axis=1)[:, None])
    distance = np.stack([np.linalg.norm(positions[:, :, None] - positions[:, mates], axis=3) for positions in labelings])
    d0 = np.linalg.norm(first[:, None] - first[mates], axis=2)
    rest = rest_lengths(labelings, mates, distance[0], d0, spread, tolerance)
    off: Array = np.abs(distance - rest)  # NaN where a pair is not labeled together
    capped: Array = np.minimum(np.where(off <= tolerance, off, cap_mm), cap_mm)  # NaN compares False: the cap
    judged: NDArray[np.bool_] = np.asarray(np.isfinite(off).any(axis=0))
    return capped, judged


def rigid_mates(labelings: list[Array], neighbours: NDArray[np.int64], partners: int) -> tuple[NDArray[np.int64], Array]:
    """``(N, partners)`` each marker's neighbours of least spread r_mj in any labeling that
    labels the pair together in at least ``SUPPORT_SHARE`` of the frames the most complete
    one does (module doc), and those spreads (variances, mm^2; NaN where none shows one)."""
    spreads = np.stack([take_spread(positions, neighbours) for positions in labelings])
    support = np.stack([_together(positions, neighbours) for positions in labelings])
    heard = support >= SUPPORT_SHARE * support.max(axis=0)
    rigidity = np.fmin.reduce(np.where(heard, spreads, np.nan), axis=0)
    order = np.argsort(np.where(np.isfinite(rigidity), rigidity, np.inf), axis=1)[:, :partners]
    mates: NDArray[np.int64] = np.take_along_axis(neighbours, order, axis=1)
    return mates, np.take_along_axis(rigidity, order, axis=1)


def _together(positions: Array, neighbours: NDArray[np.int64]) -> NDArray[np.int64]:
    """``(N, K)`` frames in which each marker and neighbour are both labeled."""
    # counted in floats: BLAS multiplies them (integer matmul took 3.4 s at 100,000 frames of
    # 68 markers, floats 0.016 s), exactly while a count is under 2^53
    labeled = np.isfinite(positions[:, :, 0]).astype(np.float64)  # (F, N)
    both: NDArray[np.int64] = np.rint(np.take_along_axis(labeled.T @ labeled, neighbours, axis=1)).astype(np.int64)
    return both
