"""The costs a permutation of a rigid set's labels is judged by (``formulations.markers.witness_costs``)."""

import numpy as np
import pytest
from rigid_scenes import SwingingSegment

from formulations.markers.pair_spread import PairSpreads
from formulations.markers.take_exchange import CAP
from formulations.markers.witness_costs import permutation_costs

# A foot: heel, ankle, fifth metatarsal, toe; 80-155 mm apart, every distance off by 50 mm or more
# when the first three go round
FOOT = np.array([[0, 0, 0], [40, 10, 70], [150, -40, 5], [190, 0, 0]], float)
WALK = SwingingSegment(turn=(0.5, 0.3, 0.9), periods=(11, 13, 7), speed=6.0, sway=40.0, hinge=1, swing=0.7, swing_period=9)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_marker_judged_by_the_one_whose_labels_it_takes_is_not_free(seed: int) -> None:
    """Heel on the ankle's point, ankle on the metatarsal's, metatarsal on the heel's: each
    permuted distance among the three is 50 mm or more off the first frame's, so every term
    is capped. The term of a marker judged by the marker whose labels it takes has no pair
    spread of its own (the marker with itself); it once came out infinite, the term free, and
    each marker's mean cost half the cap's."""
    rng = np.random.default_rng(seed)
    take = np.stack([WALK.frame(t, FOOT) for t in range(200)]) + rng.normal(0, 1.0, (200, 6, 3))
    d0 = np.linalg.norm(take[0][:, None] - take[0][None], axis=2)
    markers = [0, 1, 2]
    right, permuted = permutation_costs(take, markers, [1, 2, 0], markers, d0, PairSpreads(take))
    assert permuted[1:] == pytest.approx(np.full(199, 3 * CAP**2 / 2))
    assert np.median(right[1:]) < CAP**2 / 2  # the labels as they are fit, a third of that
