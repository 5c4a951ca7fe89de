"""Scenario loading and the cloud simulator, measured on CMU/HDM05 trial 85_02."""

from dataclasses import replace
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from service.errors import InputError
from service.evaluation.scenario import Scenario
from service.evaluation.simulate_cloud import simulate_cloud
from service.io.recording import Recording

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
SCENARIOS = Path(__file__).resolve().parents[1] / "configs" / "scenarios"


@pytest.fixture(scope="module")
def rec() -> Recording:
    c3d = ezc3d.c3d(str(DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"))
    positions = c3d["data"]["points"][:3].transpose(2, 1, 0)
    return Recording(c3d["parameters"]["POINT"]["LABELS"]["value"], positions, 120.0)


def _absent(capture) -> np.ndarray:
    """(frames, markers) bool: the marker has no point in that frame of the cloud."""
    absent = np.ones(capture.truth.positions.shape[:2], dtype=bool)
    for f, pm in enumerate(capture.point_marker):
        absent[f, pm[pm >= 0]] = False
    return absent


def _run_lengths(absent: np.ndarray) -> np.ndarray:
    """Lengths of the runs of True per column, leaving out runs cut by the last frame."""
    n = absent.shape[0]
    # Padding each column with False on both ends keeps runs from joining across columns.
    edges = np.diff(np.pad(absent.T, ((0, 0), (1, 1))).ravel().astype(int))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    cut = (ends + 1) % (n + 2) == n + 1
    return (ends - starts)[~cut]


def _residuals(capture) -> np.ndarray:
    """Every real point minus the clean position of the marker it is said to measure."""
    return np.concatenate([
        pts[pm >= 0] - capture.truth.positions[f, pm[pm >= 0]]
        for f, (pts, pm) in enumerate(zip(capture.cloud.points, capture.point_marker))
    ])


def test_shipped_scenarios_load() -> None:
    cmu = Scenario.from_toml(SCENARIOS / "cmu-85-02-cloud.toml")
    expected = dict(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0)
    assert cmu == Scenario(**expected, window=20, seed=0)
    clean = Scenario.from_toml(SCENARIOS / "clean.toml")
    assert (clean.noise_mm, clean.drop_rate, clean.ghosts_per_frame) == (0.0, 0.0, 0.0)


def test_missing_keys_take_defaults(tmp_path: Path) -> None:
    (tmp_path / "s.toml").write_text("window = 7\n")
    s = Scenario.from_toml(tmp_path / "s.toml")
    assert s == Scenario(window=7)
    assert (s.mode, s.noise_mm, s.drop_burst_frames, s.formulation) == ("cloud", 1.0, 10.0, "lp-l1")


def test_unknown_key_is_named_with_the_known_ones() -> None:
    with pytest.raises(InputError, match=r"'noise'.*noise_mm.*formulation"):
        Scenario.from_dict({"noise": 1.0})


BAD_VALUES = [("noise_mm", -0.5), ("noise_mm", "1"), ("noise_mm", float("nan")),
              ("drop_rate", 1.0), ("drop_rate", -0.1), ("drop_burst_frames", 0.5),
              ("ghosts_per_frame", -1), ("ghost_spread_mm", -1), ("window", 1), ("window", 2.5),
              ("window", True), ("seed", -1), ("start_frame", -1), ("frames", -3),
              ("formulation", ""), ("mode", "boxes")]


@pytest.mark.parametrize(
    "bad",
    [{k: v} for k, v in BAD_VALUES]
    # With bursts of one frame the deleted fraction cannot exceed 1/2.
    + [{"drop_rate": 0.6, "drop_burst_frames": 1}],
)
def test_bad_value_names_the_key(bad: dict) -> None:
    with pytest.raises(InputError, match=f"'{next(iter(bad))}'"):
        Scenario.from_dict(bad)


def test_camera_mode_needs_a_calibration_and_valid_camera_keys() -> None:
    with pytest.raises(InputError, match="'calibration'"):
        Scenario.from_dict({"mode": "cameras"})
    per_camera = Scenario.from_dict({"mode": "cameras", "calibration": "rig.toml", "association": "per-camera"})
    assert per_camera.association == "per-camera"
    with pytest.raises(InputError, match="'association'"):
        Scenario.from_dict({"mode": "cameras", "calibration": "rig.toml", "association": "per-marker"})
    with pytest.raises(InputError, match="'occlusion_rate'"):
        Scenario.from_dict({"mode": "cameras", "calibration": "rig.toml", "occlusion_rate": 1.5})


def test_unreadable_files_are_input_errors(tmp_path: Path) -> None:
    (tmp_path / "bad.toml").write_text("window = \n")
    with pytest.raises(InputError, match="not valid TOML"):
        Scenario.from_toml(tmp_path / "bad.toml")
    with pytest.raises(InputError, match="cannot read"):
        Scenario.from_toml(tmp_path / "absent.toml")


@pytest.mark.parametrize(("rate", "burst"), [(0.1, 10), (0.3, 5)])
def test_deleted_fraction_and_burst_length_match_settings(rec, rate: float, burst: int) -> None:
    absent = [_absent(simulate_cloud(rec, Scenario(drop_rate=rate, drop_burst_frames=burst,
                                                   seed=seed)))[1:] for seed in range(6)]
    assert np.mean(absent) == pytest.approx(rate, abs=0.1 * rate)
    runs = np.concatenate([_run_lengths(a) for a in absent])
    assert runs.mean() == pytest.approx(burst, rel=0.1)


@pytest.mark.parametrize("mean", [0.0, 2.0, 5.0])
def test_ghost_count_mean_matches_setting(rec, mean: float) -> None:
    capture = simulate_cloud(rec, Scenario(ghosts_per_frame=mean))
    counts = [np.sum(pm < 0) for pm in capture.point_marker]
    assert np.mean(counts) == pytest.approx(mean, abs=0.15)


def test_ghosts_sit_at_markers_when_spread_is_zero(rec) -> None:
    exact = simulate_cloud(rec, Scenario(noise_mm=0.0, ghost_spread_mm=0.0, ghosts_per_frame=3))
    for f, (pts, pm) in enumerate(zip(exact.cloud.points, exact.point_marker)):
        ghosts = pts[pm < 0][:, None]
        assert np.all(np.any(np.all(ghosts == exact.truth.positions[f], axis=2), axis=1))


def test_ghost_offsets_have_the_set_spread(rec) -> None:
    # With every marker on marker 0, a ghost's offset from it is its offset from the body.
    stacked = Recording(rec.names, np.repeat(rec.positions[:, :1], rec.n_markers, axis=1), rec.rate)
    capture = simulate_cloud(stacked, Scenario(ghosts_per_frame=3, ghost_spread_mm=150.0))
    offsets = np.concatenate([pts[pm < 0] - rec.positions[f, 0] for f, (pts, pm)
                              in enumerate(zip(capture.cloud.points, capture.point_marker))])
    assert offsets.std(axis=0) == pytest.approx([150.0] * 3, rel=0.05)
    assert np.abs(offsets.mean(axis=0)).max() < 10.0


def test_noise_std_matches_setting(rec) -> None:
    residuals = _residuals(simulate_cloud(rec, Scenario(noise_mm=2.5)))
    assert residuals.std(axis=0) == pytest.approx([2.5] * 3, rel=0.03)
    assert np.abs(residuals.mean(axis=0)).max() < 0.05


def test_point_marker_maps_each_point_to_its_marker_in_shuffled_order(rec) -> None:
    capture = simulate_cloud(rec, Scenario())
    assert np.abs(_residuals(capture)).max() < 6.0  # 6 sigma of 1 mm noise
    for pts, pm in zip(capture.cloud.points, capture.point_marker):
        assert len(pts) == len(pm)
        assert len(np.unique(pm[pm >= 0])) == np.sum(pm >= 0)
    in_order = [np.all(np.diff(pm[pm >= 0]) > 0) for pm in capture.point_marker]
    assert np.mean(in_order) < 0.01


def test_same_seed_same_capture_other_seed_differs(rec) -> None:
    a, b, c = (simulate_cloud(rec, Scenario(seed=s)) for s in (4, 4, 5))
    assert all(np.array_equal(p, q) for p, q in zip(a.cloud.points, b.cloud.points))
    assert all(np.array_equal(p, q) for p, q in zip(a.point_marker, b.point_marker))
    assert not all(np.array_equal(p, q) for p, q in zip(a.point_marker, c.point_marker))


def test_first_frame_is_intact_and_matches_the_cloud(rec) -> None:
    capture = simulate_cloud(rec, Scenario(drop_rate=0.5, start_frame=10))
    pm = capture.point_marker[0]
    assert sorted(pm[pm >= 0]) == list(range(rec.n_markers))
    first = capture.first_frame
    assert (first.names, first.n_frames) == (rec.names, 1)
    assert np.array_equal(first.positions[0, pm[pm >= 0]], capture.cloud.points[0][pm >= 0])


def test_clean_scenario_reproduces_a_slice_of_truth(rec) -> None:
    clean = replace(Scenario.from_toml(SCENARIOS / "clean.toml"), start_frame=100, frames=50)
    capture = simulate_cloud(rec, clean)
    assert np.array_equal(capture.truth.positions, rec.positions[100:150])
    assert capture.cloud.n_frames == 50
    for f, (pts, pm) in enumerate(zip(capture.cloud.points, capture.point_marker)):
        assert np.array_equal(pts[np.argsort(pm)], rec.positions[100 + f])


def test_source_gaps_stay_missing(rec) -> None:
    positions = rec.positions.copy()
    positions[10:20, 3] = np.nan
    positions[30, 4] = 0.0  # some exporters write gaps as the origin
    gappy = Recording(rec.names, positions, rec.rate)
    capture = simulate_cloud(gappy, Scenario(drop_rate=0.0))
    expected = np.zeros(positions.shape[:2], dtype=bool)
    expected[10:20, 3] = expected[30, 4] = True
    assert np.array_equal(_absent(capture), expected)
    assert np.isnan(capture.truth.positions[expected]).all()


def test_first_frame_gap_names_the_marker(rec) -> None:
    positions = rec.positions.copy()
    positions[5, 2] = np.nan
    with pytest.raises(InputError, match=f"marker {rec.names[2]} has no position in the first"):
        simulate_cloud(Recording(rec.names, positions, rec.rate), Scenario(start_frame=5))


@pytest.mark.parametrize(("start", "frames", "key"), [(810, 0, "start_frame"), (800, 11, "frames")])
def test_slice_outside_the_recording_is_refused(rec, start: int, frames: int, key: str) -> None:
    with pytest.raises(InputError, match=f"'{key}'"):
        simulate_cloud(rec, Scenario(start_frame=start, frames=frames))


def test_unnamed_markers_keep_their_points_lose_their_names_and_score_as_ghosts(rec) -> None:
    """The same cloud as without the key; three markers drop out of the names, the truth
    and the labeled frame, and their points are marked -1 (a named marker taking one took a ghost)."""
    named = simulate_cloud(rec, Scenario(seed=2, frames=50))
    unnamed = simulate_cloud(rec, Scenario(seed=2, frames=50, unnamed_markers=3))
    assert all(np.array_equal(p, q) for p, q in zip(named.cloud.points, unnamed.cloud.points))
    kept = [rec.names.index(n) for n in unnamed.truth.names]
    gone = sorted(set(range(rec.n_markers)) - set(kept))
    assert len(gone) == 3 and unnamed.first_frame.names == unnamed.truth.names
    assert np.array_equal(unnamed.truth.positions, named.truth.positions[:, kept], equal_nan=True)
    assert np.array_equal(unnamed.first_frame.positions[0], named.first_frame.positions[0, kept])
    for old, new in zip(named.point_marker, unnamed.point_marker):
        was_gone = np.isin(old, gone)
        assert np.all(new[was_gone | (old < 0)] == -1)
        assert np.array_equal(np.array(kept)[new[~was_gone & (old >= 0)]], old[~was_gone & (old >= 0)])


def test_unnamed_markers_need_the_cloud_and_fewer_than_the_take(rec) -> None:
    with pytest.raises(InputError, match="unnamed_markers"):
        Scenario(mode="cameras", calibration="x.toml", unnamed_markers=2)
    with pytest.raises(InputError, match="unnamed_markers"):
        simulate_cloud(rec, Scenario(frames=5, unnamed_markers=rec.n_markers))


@pytest.mark.parametrize(("keys", "said"), [
    ({"pixel_noise": 9000.0}, "'pixel_noise' applies to mode = \"cameras\"; this scenario's mode is \"cloud\""),
    ({"mode": "cameras", "calibration": "c.toml", "noise_mm": 500.0}, "'noise_mm' applies to mode = \"cloud\""),
    ({"formulation_parameters": {"time_limit": 1e-4}}, "unknown scenario key 'formulation_parameters'"),
    ({"mode": "cameras", "calibration": "c.toml", "second_pass": False}, "'second_pass' applies to mode = \"cloud\""),
])
def test_a_key_the_mode_ignores_is_refused(keys: dict, said: str) -> None:
    """They were accepted and changed nothing (or, undocumented, changed the formulation)."""
    with pytest.raises(InputError, match=said):
        Scenario.from_dict(keys)
    assert Scenario.from_dict({"formulation": {"name": "lp-l1", "time_limit": 5.0}}).formulation_parameters == {
        "time_limit": 5.0}
