"""What one window hands the next about each marker (Jiang Sec. II-E: the template)."""

from __future__ import annotations

import weakref
from dataclasses import dataclass, fields, replace
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from formulations.markers.motion import DRIFT_VAR_PRIOR_MM2, MOTION_VAR_PRIOR_MM2, learn_burst, learn_drift, learn_motion
from formulations.markers.motion_filter import advance_filter, filter_predicts, initial_filter
from formulations.markers.rejoined import rejoined_velocity
from formulations.markers.rigid import FIRM_INLIERS, follow_neighbours
from formulations.markers.rigid import RIGID_SD_MM as RIGID_SD_MM

SURE_STREAK = 3  # frames in a row a marker's point must have been its own to vouch for where it was


@dataclass(frozen=True)
class MarkerState:
    """Per-marker state at a template frame.

    Attributes:
        position: ``(N, 3)`` last labeled position, or the prediction while unseen.
        velocity: ``(N, 3)`` displacement per frame.
        velocity_known: ``(N,)`` False until a marker has been seen in two consecutive
            frames (the labeled first frame alone says nothing about motion).
        unseen: ``(N,)`` frames since the marker was last labeled (0 = seen now).
        streak: ``(N,)`` consecutive frames the marker has been seen up to now.
        neighbours: ``(N, K)`` the K markers nearest each marker in the first frame.
        anchor: ``(N, 3)`` where each marker was last seen, and ``anchor_neighbours``
            ``(N, K, 3)`` where its neighbours were at that frame (``anchor_valid``
            ``(N, K)``: the neighbour was seen then; ``anchor_carried`` ``(N, K)``: it was
            not, but a firm rigid fit carried it, to within ``RIGID_SD_MM`` per axis, so its
            anchor position is a sure prediction).
            While a marker is occluded, the rigid motion of its neighbours since that frame
            carries it along.
        seen_at: ``(N, 3)`` the point each marker last took (never carried); NaN where unknown
            (placed by a model, dropped by a repair) or held under ``SURE_STREAK`` frames in a row.
        distance_mean, distance_var: ``(N, K)`` running mean and variance of each
            marker-neighbour distance (mm, mm^2). Neighbours on the same rigid segment keep
            their distance and are trusted most: Ringer & Lasenby's (2004) grouping by the
            variance of inter-marker distances, kept online.
        motion_var: ``(N,)`` variance per axis (mm^2) of each marker's constant-velocity
            residual x_t - 2 x_(t-1) + x_(t-2), i.e. 6 sigma^2 + q_n^2 (``noise.TakeNoise``):
            the take's own noise and the marker's own acceleration, learned as it is labeled
            (``motion.learn_motion``: an envelope that calm lowers slowly).
        motion_samples: ``(N,)`` residuals that went into ``motion_var``.
        burst_var: ``(N,)`` the same residual's persisting part over the last few frames, per
            axis (``motion.learn_burst``, from lag products): high while a limb accelerates,
            about 0 under noise alone, 0 when unknown.
        last_residual: ``(N, 3)`` the last frame's motion residual, 0 where it had none.
        drift_var, drift_samples: ``(N,)`` how fast (mm^2 per axis per frame unseen) an occluded
            marker's prediction drifts, and the reappearances it was learned from
            (``motion.learn_drift``; one value for all markers: reappearances are rare).
        plate_position, plate_age, plate_rate: ``(N, 3)``, ``(N,)``, ``(N,)`` where each marker was
            when its rigid plate (``turns.rigid_triples``) was last seen whole, how many frames ago
            (-1: never), and how fast it turned then (rad per frame, NaN unknown; ``turns``).
        filtered, filter_cov, filter_raw, residual_var, filter_var, noise_var, noise_samples:
            each marker's Kalman filter and what decides where it predicts (``motion_filter.advance_filter``).
    """

    position: np.ndarray
    velocity: np.ndarray
    velocity_known: np.ndarray
    unseen: np.ndarray
    streak: np.ndarray
    neighbours: np.ndarray
    anchor: np.ndarray
    anchor_neighbours: np.ndarray
    anchor_valid: np.ndarray
    anchor_carried: np.ndarray
    seen_at: np.ndarray
    distance_mean: np.ndarray
    distance_var: np.ndarray
    motion_var: np.ndarray
    motion_samples: np.ndarray
    burst_var: np.ndarray
    last_residual: np.ndarray
    drift_var: np.ndarray
    drift_samples: np.ndarray
    plate_position: np.ndarray
    plate_age: np.ndarray
    plate_rate: np.ndarray
    filtered: np.ndarray
    filter_cov: np.ndarray
    filter_raw: np.ndarray
    residual_var: np.ndarray
    filter_var: np.ndarray
    noise_var: np.ndarray
    noise_samples: np.ndarray

    @classmethod
    def from_first_frame(cls, position: np.ndarray, n_neighbours: int = 16) -> MarkerState:
        """State from a labeled first frame (all markers visible, velocity unknown)."""
        position = np.asarray(position, dtype=float)
        n = len(position)
        k = min(n_neighbours, n - 1)
        _, idx = cKDTree(position).query(position, k=k + 1)
        neighbours = np.asarray(idx, dtype=int).reshape(n, k + 1)[:, 1:]
        return cls(
            position=position, velocity=np.zeros_like(position), velocity_known=np.zeros(n, bool),
            unseen=np.zeros(n, int), streak=np.ones(n, int), neighbours=neighbours, anchor=position.copy(),
            anchor_neighbours=position[neighbours], anchor_valid=np.ones(neighbours.shape, bool),
            anchor_carried=np.zeros(neighbours.shape, bool), seen_at=position.copy(),
            distance_mean=np.linalg.norm(position[:, None] - position[neighbours], axis=2),
            distance_var=np.full(neighbours.shape, 100.0),
            motion_var=np.full(n, MOTION_VAR_PRIOR_MM2), motion_samples=np.zeros(n, int),
            burst_var=np.zeros(n), last_residual=np.zeros((n, 3)),
            drift_var=np.full(n, DRIFT_VAR_PRIOR_MM2), drift_samples=np.zeros(n, int),
            plate_position=np.full((n, 3), np.nan), plate_age=np.full(n, -1), plate_rate=np.full(n, np.nan), **initial_filter(n),
        )

    def __getstate__(self) -> dict[str, object]:
        """Its fields only, for another process (``rival_process``): what ``cached_property``
        derived from them is derived again there, and ``_advanced``'s weak dictionary cannot travel."""
        return {field.name: getattr(self, field.name) for field in fields(self)}

    @cached_property
    def visible(self) -> np.ndarray:
        """``(N,)`` seen at the template frame (computed once per state: not to be written into)."""
        return np.asarray(self.unseen == 0)

    def advance(self, observed: np.ndarray, seen: np.ndarray, damping: float = 0.8, rate: float = 0.03) -> MarkerState:
        """The state one frame later.

        The guide track advances a window's states, and the window's labels advance them again,
        mostly with the same points: an advance already made is not made twice (``_advanced``).

        Args:
            observed: ``(N, 3)`` positions taken this frame (ignored where not ``seen``).
            seen: ``(N,)`` bool, markers labeled this frame.
            damping: Velocity factor per unseen frame: occluded markers slow down rather
                than fly off on a stale velocity.
            rate: Weight of the newest frame in the running distance statistics.
        """
        seen = np.asarray(seen, dtype=bool)
        key = (np.asarray(observed, dtype=float).tobytes(), seen.tobytes(), damping, rate)
        if (state := self._advanced.get(key)) is None:  # the name holds it: the dictionary only weakly
            state = self._advanced[key] = self._advance(observed, seen, damping, rate)
        return state

    @cached_property
    def _advanced(self) -> weakref.WeakValueDictionary[tuple[bytes, bytes, float, float], MarkerState]:
        """The states this one was advanced to, while anything else holds them (``test_state_memory``)."""
        return weakref.WeakValueDictionary()

    def _advance(self, observed: np.ndarray, seen: np.ndarray, damping: float, rate: float) -> MarkerState:
        """``advance`` computed."""
        predicted, followed, carriers = self._prediction
        carried = np.asarray(carriers.any(axis=1))  # a firm fit has FIRM_INLIERS carriers or more
        rejected = carried[:, None] & self._followable & ~carriers
        position = np.where(seen[:, None], observed, predicted)
        was_seen = self.visible & seen
        # Seen twice: measured. Otherwise the displacement the neighbours imply (a stale
        # velocity from before a gap is wrong for a fast limb), else damped.
        implied = np.where(followed[:, None], predicted - self.position, self.velocity * damping)
        velocity = np.where(was_seen[:, None], observed - self.position, implied)
        velocity = rejoined_velocity(self, velocity, seen & ~self.visible, was_seen, position)
        residual = observed - predicted
        usable = seen & (self.streak >= 2)
        motion_var, motion_samples = learn_motion(self.motion_var, self.motion_samples, residual, usable)
        drift_var, drift_samples = learn_drift(
            self.drift_var, self.drift_samples, residual, seen & ~self.visible, self.unseen, self.motion_var,
        )
        # A marker carried by a firm rigid fit re-anchors at its prediction when a neighbour it
        # followed is lost (it may have been the only one on its segment): the rest carry it on
        # from there. A loose fit is not locked in: its error would compound.
        anchored = seen | (carried & (self.anchor_valid & ~seen[self.neighbours]).any(axis=1))
        # Distances learn from sightings only: a carried position is the labeler's own guess, and
        # a pair learned from it confirms the guess as the shape (CMU 85_02's thigh marker, carried
        # by the pelvis, learned its knee pair at 341 mm, truly 219, and drifted 300 mm). What a carried
        # marker moves with is its fit's ``carriers`` instead.
        # A carried position counts as an anchor only while its own prediction is sure to
        # within what a rigid pair's distance varies by: not in fast motion.
        sure_carry = carried & ~seen & (self.prediction_var(self.unseen) < RIGID_SD_MM**2)
        both = seen[:, None] & seen[self.neighbours]
        around = np.take(position, self.neighbours, axis=0)  # (N, K, 3), once; np.take gathers rows faster than indexing
        deviation = np.linalg.norm(position[:, None] - around, axis=2) - self.distance_mean
        return replace(
            self, position=position, velocity=velocity, velocity_known=self.velocity_known | was_seen,
            unseen=np.where(seen, 0, self.unseen + 1), streak=np.where(seen, self.streak + 1, 0),
            anchor=np.where(anchored[:, None], position, self.anchor),
            anchor_neighbours=np.where(anchored[:, None, None], around, self.anchor_neighbours),
            # Re-anchored while carried: the neighbours the fit found not moving with it stay out
            # (a lifting wrist that loses its ulnar mate must not fall back onto the still thigh).
            anchor_valid=np.where(anchored[:, None], seen[self.neighbours] & ~rejected, self.anchor_valid),
            anchor_carried=np.where(anchored[:, None], sure_carry[self.neighbours], self.anchor_carried),
            seen_at=np.where(seen[:, None], np.where((self.streak >= SURE_STREAK - 1)[:, None], observed, np.nan),
                             self.seen_at),
            distance_mean=np.where(both, self.distance_mean + rate * deviation, self.distance_mean),
            distance_var=np.where(both, (1 - rate) * (self.distance_var + rate * deviation**2), self.distance_var),
            motion_var=motion_var, motion_samples=motion_samples,
            burst_var=learn_burst(self.burst_var, residual, self.last_residual, usable, self.step_var),
            last_residual=np.where(usable[:, None], residual, 0.0),
            drift_var=drift_var, drift_samples=drift_samples, **advance_filter(self, observed, seen, residual, usable),
        )

    def neighbour_motion(
        self, rows: np.ndarray, usable: np.ndarray, source: np.ndarray, target: np.ndarray, motion_var: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The robust rigid motion (``follow_neighbours``) of markers ``rows``' usable
        neighbours from ``source`` to ``target`` ``(R, K, 3)``; a translation with fewer than three.
        The last element is the fit's inliers ``(R, K)`` (``follow_neighbours``)."""
        # Rigidity prior: the learned distance variance, and nearness (a neighbour twice as
        # far is a quarter as likely to share the marker's segment); see ``follow_neighbours``.
        spacing = np.maximum(self.distance_mean[rows], 1.0)
        prior = usable / ((self.distance_var[rows] + 1.0) * spacing**2)
        rotation, c_s, c_t, inliers = follow_neighbours(source, target, prior, motion_var)
        rotation[usable.sum(axis=1) < 3] = np.eye(3)
        return rotation, c_s, c_t, inliers

    @property
    def step_var(self) -> np.ndarray:
        """``(N,)`` per-axis variance (mm^2) of the next constant-velocity step's residual:
        the take's learned envelope, or the last frames' burst when that is wider."""
        var: np.ndarray = np.maximum(self.motion_var, self.burst_var)
        return var

    def prediction_var(self, unseen: np.ndarray) -> np.ndarray:
        """Per-axis variance (mm^2) of a prediction ``unseen + 1`` frames past the last sighting:
        one frame's motion residual plus the learned drift per further frame."""
        var: np.ndarray = self.step_var + self.drift_var * unseen
        return var

    def predict(self) -> np.ndarray:
        """``(N, 3)`` predicted position one frame ahead: the Kalman filter's where it predicts
        (``motion_filter.filter_predicts``), else ``_prediction``'s."""
        return np.where(filter_predicts(self)[:, None], self.filtered[:, 0] + self.filtered[:, 1], self._prediction[0])

    @property
    def carriers(self) -> np.ndarray:
        """``(N, K)`` for a marker a firm rigid fit carries into the next frame, the neighbours
        that fit found moving with it (its segment, as far as the take has shown); False elsewhere."""
        return self._prediction[2]

    def stranded(self, after: int) -> np.ndarray:
        """``(N,)`` unseen for ``after`` frames or more with no seen neighbour to follow:
        nothing carries these markers but a damped stale velocity."""
        stranded: np.ndarray = (self.unseen >= after) & ~self._followable.any(axis=1)
        return stranded

    @cached_property
    def _followable(self) -> np.ndarray:
        """``(N, K)`` neighbours seen both at the marker's anchor frame and now; and for a
        marker with fewer than three such neighbours rigid with it (learned sd under
        ``RIGID_SD_MM``), also those a firm fit carried at its anchor frame, with a
        prediction sd then under ``RIGID_SD_MM`` per axis (``anchor_carried``), and seen now.

        A foot's markers lost in turn: CMU 85_02's right fifth metatarsal, last seen while the
        heel and toe were hidden, followed the ankle and shank across the joint and drifted
        6 -> 72 mm in 22 frames, though heel and toe were back after 3 and 11 (2 mm noise,
        seed 0); it then took the toe's point. Their predicted positions at its last sighting
        let it follow the foot (under 7 mm). Only as a fallback, and only sure predictions: a
        carried position has its own error, large in fast motion (every carried neighbour
        counting cost the seed-0 matrix 1.7 points: docs/how-a-window-is-solved.md). Once per
        state (the guide asks twice a frame, the prediction once): not to be written into."""
        seen_now = self.visible[self.neighbours]
        usable: np.ndarray = self.anchor_valid & seen_now
        short = (usable & (self.distance_var < RIGID_SD_MM**2)).sum(axis=1) < 3
        usable[short] |= (self.anchor_carried & seen_now)[short]
        return usable

    @cached_property
    def _prediction(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Predicted positions, which markers followed their neighbours, and ``carriers`` (a firm
        rigid fit's, ``rigid.follow_neighbours``); computed once per state (the
        labeler predicts a state, then advances it), so never to be written into.

        Constant velocity for markers seen now. An unseen marker follows the neighbours
        seen both at its anchor frame and now: their robust rigid motion (near neighbours
        on the same segment dominate) applied to its anchor; a translation when fewer than
        three such neighbours remain; damped constant velocity when none does.
        """
        ahead = self.position + self.velocity
        usable = self._followable
        followed = ~self.visible & usable.any(axis=1)
        follow = np.flatnonzero(followed)
        carriers = np.zeros(self.neighbours.shape, bool)
        if len(follow) == 0:
            return ahead, followed, carriers
        rotation, c_s, c_t, inliers = self.neighbour_motion(
            follow, usable[follow], self.anchor_neighbours[follow], ahead[self.neighbours[follow]], self.motion_var[follow],
        )
        predicted = ahead.copy()
        predicted[follow] = np.einsum("sij,sj->si", rotation, self.anchor[follow] - c_s) + c_t
        carriers[follow] = inliers & (inliers.sum(axis=1) >= FIRM_INLIERS)[:, None]
        return predicted, followed, carriers
