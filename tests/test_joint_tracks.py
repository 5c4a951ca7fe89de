"""A segment that loses two of its three markers: its joint centres as fill donors, and its pose where they disagree."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from test_subject_model import chain

from formulations.markers.rigid_fill import rigid_fill
from formulations.subject.fit import fit_subject
from formulations.subject.geometry import ModelGeometry
from formulations.subject.joint_tracks import GUIDE_RMS_MM, joint_tracks
from formulations.subject.pose_fill import pose_fill
from service.capture.model_input import model_names

FIT = 200


def _held_out(seed: int):
    names, positions, centres = chain(seed, markers=3, frames=400)
    model = fit_subject(names, positions[:FIT]).model
    order = model_names(model)
    held = positions[FIT:, [names.index(n) for n in order]]
    return ModelGeometry.of(model), order, held, [c[FIT:] for c in centres]


def test_each_side_places_the_joint_centre_where_it_is() -> None:
    geometry, order, held, centres = _held_out(0)
    tracks, serves = joint_tracks(geometry, order, held)
    joints = len(geometry.joints)
    for k in range(2 * joints):
        truth = min(centres, key=lambda c: np.nanmedian(np.linalg.norm(tracks[:, k] - c, axis=1)))
        assert np.median(np.linalg.norm(tracks[:, k] - truth, axis=1)) < 6.0
        joint = geometry.joints[k % joints]
        other = joint.b if k < joints else joint.a
        assert {order[i] for i in np.flatnonzero(serves[k])} == {geometry.names[m] for m in geometry.segments[other].markers}


def test_a_centre_is_not_placed_from_the_gap_it_would_fill() -> None:
    geometry, order, held, _ = _held_out(1)
    hidden = held.copy()
    segment = geometry.segments[1]
    hidden[50:60, segment.markers[0]] = np.nan  # the segment keeps two markers: no pose of its own
    tracks, _ = joint_tracks(geometry, order, hidden)
    own = [k for k, j in enumerate(geometry.joints) if j.a == 1] + [
        len(geometry.joints) + k for k, j in enumerate(geometry.joints) if j.b == 1]
    assert own and np.isnan(tracks[50:60, own]).all()
    assert np.isfinite(tracks[40:50, own]).all()


def test_two_markers_lost_together_are_carried_by_the_joints() -> None:
    for seed in range(3):
        geometry, order, held, _ = _held_out(seed)
        middle = next(s for s in range(len(geometry.segments)) if sum(s in (j.a, j.b) for j in geometry.joints) == 2)
        lost = geometry.segments[middle].markers[:2]  # one mate left: with no joint, nothing fixes its turn
        positions = held.copy()
        positions[80:120, lost] = np.nan
        truth = held[80:120, lost]
        unfilled = np.where(np.isfinite(positions), positions, 0.0)
        alone = rigid_fill(positions, unfilled)[80:120, lost]
        guided = rigid_fill(positions, unfilled, joint_tracks(geometry, order, positions))[80:120, lost]
        error_alone = np.sqrt(np.mean(np.sum((alone - truth) ** 2, axis=-1)))
        error_guided = np.sqrt(np.mean(np.sum((guided - truth) ** 2, axis=-1)))
        assert error_guided < 0.5 * error_alone
        assert error_guided < 8.0


def _gap_of_two(seed: int):
    """The held-out take with two of a middle segment's three markers lost for 40 frames, a
    fill that bows up to 100 mm off where they are (tying it to the sightings does not
    straighten it), and which markers."""
    geometry, order, held, _ = _held_out(seed)
    middle = next(s for s in range(len(geometry.segments)) if sum(s in (j.a, j.b) for j in geometry.joints) == 2)
    lost = geometry.segments[middle].markers[:2]
    positions = held.copy()
    positions[80:120, lost] = np.nan
    bow = 100.0 * np.sin(np.pi * (np.arange(len(held)) - 79) / 41)[:, None, None]
    wrong = np.where(np.isfinite(positions), positions, held + bow)
    return geometry, order, held, positions, wrong, lost


def test_where_the_rigid_carries_disagree_the_segment_pose_fills() -> None:
    geometry, order, held, positions, wrong, lost = _gap_of_two(0)
    doubt = np.where(np.isfinite(positions).all(axis=2), 0.0, np.inf)
    filled = pose_fill(geometry, order, positions, wrong, doubt)
    error = np.linalg.norm(filled[80:120, lost] - held[80:120, lost], axis=-1)
    assert np.sqrt(np.mean(error**2)) < 6.0  # the bowed fill, replaced by the tied pose
    seen = np.isfinite(positions).all(axis=2)
    assert np.array_equal(filled[seen], wrong[seen])


def test_where_the_rigid_carries_agree_their_fill_stays() -> None:
    geometry, order, held, positions, wrong, lost = _gap_of_two(1)
    doubt = np.where(np.isfinite(positions).all(axis=2), 0.0, 1.0)  # 1 mm^2: well under any tolerance
    assert np.array_equal(pose_fill(geometry, order, positions, wrong, doubt), wrong)


def test_a_poorly_placed_joint_poses_nothing() -> None:
    geometry, order, held, positions, wrong, lost = _gap_of_two(2)
    poor = replace(geometry, joints=[replace(j, rms=2 * GUIDE_RMS_MM) for j in geometry.joints])
    doubt = np.where(np.isfinite(positions).all(axis=2), 0.0, np.inf)
    filled = pose_fill(poor, order, positions, wrong, doubt)
    assert np.linalg.norm(filled[90:110, lost] - held[90:110, lost], axis=-1).min() > 50.0
