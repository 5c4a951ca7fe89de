"""A doubt is lifted only by the shape the marker had when last trusted: a right label comes
back to confident, an exchange the learned shape has already adapted to stays doubtful."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from formulations.confidence.shape import shape_identity
from formulations.confidence.trusted_shape import TrustedShape, confirmed
from formulations.markers.state import MarkerState
from service.labeling.confidence import IdentityCarry, lifted
from service.labeling.stats import DOUBTFUL_BELOW

FRAMES = 5
BODY = np.array([[0, 0, 0], [60, 0, 0], [0, 80, 0], [0, 0, 90], [70, 70, 0], [50, 0, 100]], dtype=float)


def _state(position: np.ndarray) -> MarkerState:
    """Six markers of one rigid body seen for a while at ``position``, their distances learned
    there (s.d. 2 mm); neighbours as chosen on the body's first frame, as in a labeling run."""
    state = MarkerState.from_first_frame(BODY, n_neighbours=5)
    mean = np.linalg.norm(position[:, None] - position[state.neighbours], axis=2)
    return replace(
        state, position=position.copy(), distance_mean=mean, distance_var=np.full(mean.shape, 4.0),
        streak=np.full(len(position), 40),
    )


def _exchanged() -> np.ndarray:
    """Markers 0 and 1 hold each other's points."""
    return BODY[[1, 0, 2, 3, 4, 5]]


def test_the_trusted_shape_tells_an_exchange_the_learned_shape_has_adapted_to() -> None:
    adapted = _state(_exchanged())  # the statistics learned the exchange over many frames
    trusted = TrustedShape.of(_state(BODY))
    judged = np.array([0, 1])
    assert (shape_identity(adapted, adapted, judged) > 0.99).all()  # what the learned shape says: fine
    assert (confirmed(trusted, adapted, judged, np.ones(6, bool), DOUBTFUL_BELOW) < 0.01).all()


def test_a_right_label_is_confirmed_and_thin_evidence_says_nothing() -> None:
    end = _state(BODY + np.array([3.0, -2.0, 1.0]))
    trusted = TrustedShape.of(_state(BODY))
    assert confirmed(trusted, end, np.array([0]), np.ones(6, bool), DOUBTFUL_BELOW)[0] > DOUBTFUL_BELOW
    only_one = np.array([True, True, False, False, False, False])  # one trusted neighbour of 0
    assert np.isnan(confirmed(trusted, end, np.array([0]), only_one, DOUBTFUL_BELOW)[0])
    loose = replace(trusted, distance_var=np.full(trusted.distance_var.shape, 400.0))  # nothing rigid
    assert np.isnan(confirmed(loose, end, np.array([0]), np.ones(6, bool), DOUBTFUL_BELOW)[0])


def test_a_limb_doubted_as_a_whole_vouches_for_itself_unless_exchanged_inside() -> None:
    """No marker of the body is trusted, so none has a trusted neighbour to be judged by:
    only the doubtful markers the trusted shape confirms can vouch for each other."""
    trusted = TrustedShape.of(_state(BODY))
    nobody = np.zeros(6, bool)
    everyone = np.arange(6)
    right = confirmed(trusted, _state(BODY + np.array([3.0, -2.0, 1.0])), everyone, nobody, DOUBTFUL_BELOW)
    assert (right > DOUBTFUL_BELOW).all()
    exchanged = confirmed(trusted, _state(_exchanged()), everyone, nobody, DOUBTFUL_BELOW)
    assert not (np.nan_to_num(exchanged[:2], nan=0.0) > DOUBTFUL_BELOW).any()  # the pair stays doubtful
    alone = np.array([0, 1])  # the rest neither trusted nor doubtful here: nothing vouches
    assert np.isnan(confirmed(trusted, _state(BODY), alone, nobody, DOUBTFUL_BELOW)).all()


def _lift(end: MarkerState) -> tuple[np.ndarray, IdentityCarry]:
    """A window where markers 0 and 1 come in doubtful (carry 0.05) and are seen throughout."""
    before = np.array([0.05, 0.05, 1, 1, 1, 1])
    own = np.full((FRAMES, 6), 0.99)
    confidence = own * before[None]
    carry = IdentityCarry(before.copy(), TrustedShape.of(_state(BODY)))
    return lifted(confidence, own, np.zeros((FRAMES, 6), bool), carry, end)


def test_a_doubt_the_trusted_shape_settles_is_lifted_and_an_exchange_stays() -> None:
    right, carry = _lift(_state(BODY))
    assert (right[:, :2] >= DOUBTFUL_BELOW).all() and (carry.confidence[:2] >= DOUBTFUL_BELOW).all()
    wrong, carry = _lift(_state(_exchanged()))
    assert (wrong[:, :2] < DOUBTFUL_BELOW).all() and (carry.confidence[:2] < DOUBTFUL_BELOW).all()
    # A doubtful marker keeps its trusted shape; the trusted ones hand on what they learned.
    assert np.array_equal(carry.shape.distance_mean[:2], TrustedShape.of(_state(BODY)).distance_mean[:2])
    assert np.array_equal(carry.shape.distance_mean[2:], _state(_exchanged()).distance_mean[2:])


def test_only_the_labels_since_the_sighting_began_are_lifted() -> None:
    end = replace(_state(BODY), streak=np.array([2, 40, 40, 40, 40, 40]))  # 0 re-acquired 2 frames ago
    confidence, _ = _lift(end)
    assert (confidence[-2:, 0] >= DOUBTFUL_BELOW).all()
    assert (confidence[:-2, 0] < DOUBTFUL_BELOW).all()


def test_what_a_doubtful_label_taught_the_shape_is_forgotten() -> None:
    # Markers 0 and 1 exchanged long enough for the statistics to learn it; 0 and 1 are doubtful.
    adapted = _state(_exchanged())
    trusted = TrustedShape.of(_state(BODY))
    carry = IdentityCarry(np.array([0.05, 0.05, 1, 1, 1, 1]), trusted)
    state = carry.forget_doubtful(adapted)
    assert np.array_equal(state.distance_mean[:2], trusted.distance_mean[:2])
    assert np.array_equal(state.distance_mean[2:], adapted.distance_mean[2:])
    # Judged by what it has learned now, the exchange no longer fits: the repair can see it.
    assert (shape_identity(state, adapted, np.array([0, 1])) < 0.01).all()
    assert (shape_identity(adapted, adapted, np.array([0, 1])) > 0.99).all()


def test_a_marker_never_seen_has_no_trusted_shape_to_go_back_to() -> None:
    # A subject model's start: marker 0 unnamed (its statistics a guess), later acquired doubtful.
    start = replace(_state(BODY), unseen=np.array([5, 0, 0, 0, 0, 0]))
    shape = TrustedShape.of(start)
    assert shape.known.tolist() == [False, True, True, True, True, True]
    learned = _state(BODY + 1.0)
    kept = IdentityCarry(np.array([0.05, 1, 1, 1, 1, 1]), shape).forget_doubtful(learned)
    assert np.array_equal(kept.distance_mean[0], learned.distance_mean[0])  # nothing to forget back to
    assert not shape.updated(start, np.ones(6, bool)).known[0]  # trusted but unseen: still no shape
    assert shape.updated(_state(BODY), np.ones(6, bool)).known.all()  # seen and trusted: it has one
    assert np.isnan(confirmed(shape, _state(BODY), np.array([0]), np.ones(6, bool), DOUBTFUL_BELOW)[0])
