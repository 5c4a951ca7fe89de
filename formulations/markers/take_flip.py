"""Recovery over a whole labeled take: a rigid plate of four markers read turned half round,
two pairs exchanged at once, given back on the say of the labeled first frame.

A wrist and hand carry four markers rigid with one another: the radial and ulnar styloids
and the second and fifth metacarpal heads. Turned half round about the forearm's axis they
sit on one another's points in pairs, radial on ulnar and second on fifth, and the plate's
own distances barely change. numediart's 03_rolling, relabeled from frame 562: the left
hand lost for up to 270 frames came back so at frame 1139 and stayed so for 340 frames
(1,450 wrong labels). No pair exchange (``take_exchange``) undoes it: a pair's witnesses
are the markers rigid with both, and two of the styloids' four are the exchanged metacarpal
pair, which, turned with them, vote for the labels as they are, against the elbow's two.

So the plate is judged as a whole, by the rotation's judge
(``take_rotation.judged_permutation``): a pair (a, b) and a pair (c, d), each among the
other's ``NEAREST`` nearest in the first frame, all six distances rigid over the take
(``take_exchange.rigid_pairs``), and the permutation a <-> b, c <-> d, whose witnesses are
the markers rigid with all four. It gives the exchanges back over the run the judge finds,
with its bars for four markers' costs (twice the exchange's). Best first, each judged on the
labels the ones before left; pair exchanges and rotations go first.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
from numpy.typing import NDArray

from formulations.markers.pair_spread import PairSpreads
from formulations.markers.take_exchange import NEAREST, TakeExchange, near_pairs, rigid_pairs
from formulations.markers.take_rotation import judged_permutation

Array = NDArray[np.float64]
Plate = tuple[tuple[int, int], tuple[int, int]]


def take_flips(positions: Array, first: Array, neighbours: NDArray[np.int64], predicted: Array | None = None,
               ) -> list[TakeExchange]:
    """The half turns that give a labeling back its first frame's shape (module doc), each as
    its two exchanges over the same frames, in the order they apply; arguments as
    ``take_exchange.take_exchanges``."""
    d0 = np.linalg.norm(first[:, None] - first[None], axis=2)
    _, rigid = rigid_pairs(positions, first, neighbours)
    continued = positions if predicted is None else np.where(np.isfinite(positions), positions, predicted)
    working, done = np.stack([positions, continued]), []
    spreads = PairSpreads(working[0])
    plates = _plates(near_pairs(neighbours, NEAREST) & rigid)
    while plates:
        found = [(run, plate) for plate in plates if (run := _judged(working, plate, neighbours, d0, spreads))]
        if not found:
            break
        (start, stop, nats), ((a, b), (c, d)) = max(found, key=lambda f: f[0][2])
        working[:, start:stop, [a, b, c, d]] = working[:, start:stop, [b, a, d, c]]
        spreads = PairSpreads(working[0])
        done += [TakeExchange(a, b, start, stop, nats / 2), TakeExchange(c, d, start, stop, nats / 2)]
        plates = [p for p in plates if {*p[0], *p[1]} != {a, b, c, d}]
    return done


def _plates(linked: NDArray[np.bool_]) -> list[Plate]:
    """Every two disjoint ``linked`` pairs whose four markers are linked pairwise (``linked``:
    near and rigid)."""
    pairs = [(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(linked, 1)))]
    return [(p, q) for p, q in combinations(pairs, 2)
            if not {*p} & {*q} and all(linked[i, j] for i in p for j in q)]


def _judged(tracks: Array, plate: Plate, neighbours: NDArray[np.int64], d0: Array, spreads: PairSpreads,
            ) -> tuple[int, int, float] | None:
    """The plate's half turn over its best frames, None when it does not clear."""
    (a, b), (c, d) = plate
    return judged_permutation(tracks, [a, b, c, d], [b, a, d, c], neighbours, d0, spreads)
