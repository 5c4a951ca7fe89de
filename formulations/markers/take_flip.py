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

So the plate is judged as a whole, by the rotation's search
(``take_rotation.permutations_given_back``): a pair (a, b) and a pair (c, d), each among the
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
from formulations.markers.take_rotation import permutations_given_back

Array = NDArray[np.float64]


def take_flips(positions: Array, first: Array, neighbours: NDArray[np.int64], predicted: Array | None = None,
               ) -> list[TakeExchange]:
    """The half turns that give a labeling back its first frame's shape (module doc), each as
    its two exchanges over the same frames, in the order they apply; arguments as
    ``take_exchange.take_exchanges``."""
    _, rigid = rigid_pairs(positions, first, neighbours)
    sets = [[((a, b, c, d), (b, a, d, c))] for (a, b), (c, d) in _plates(near_pairs(neighbours, NEAREST) & rigid)]
    given = permutations_given_back(positions, first, neighbours, predicted, sets, PairSpreads(positions))
    return [exchange for ((a, b, c, d), _), start, stop, nats in given
            for exchange in (TakeExchange(a, b, start, stop, nats / 2), TakeExchange(c, d, start, stop, nats / 2))]


def _plates(linked: NDArray[np.bool_]) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """Every two disjoint ``linked`` pairs whose four markers are linked pairwise (``linked``:
    near and rigid)."""
    pairs = [(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(linked, 1)))]
    return [(p, q) for p, q in combinations(pairs, 2)
            if not {*p} & {*q} and all(linked[i, j] for i in p for j in q)]
