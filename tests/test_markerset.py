"""Marker-set templates: the shipped ones load, a static take fits, mistakes are one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from typer.testing import CliRunner

from formulations.errors import FormulationError
from formulations.subject.model import SubjectModel
from formulations.subject.template import Template, base_name, fit_template
from service.capture.markerset import load_template, shipped
from service.cli.app import app
from service.errors import InputError
from service.io.formats import read_labeled

STATIC = DATA / "mocap_opensim" / "rajagopal_static_run.trc"


def test_every_shipped_template_loads_and_names_segments_its_joints_use() -> None:
    assert {"cmu-41", "plug-in-gait", "gait2354", "rajagopal"} <= set(shipped())
    for name in shipped():
        template = load_template(name)
        for (a, b), centre in template.joints:
            assert a in template.segments and b in template.segments and centre


def test_unknown_name_and_bad_keys_are_one_line(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="unknown marker set 'nope'"):
        load_template("nope")
    bad = tmp_path / "bad.toml"
    bad.write_text('[segments]\na = ["X", "Y", "Z"]\n[[joints]]\nsegments = ["a", "b"]\ncentre = ["X"]\n')
    with pytest.raises(InputError, match="joints.0.segments must name two segments"):
        load_template(str(bad))
    with pytest.raises(FormulationError, match="skin_mm must be a number"):
        Template.from_dict({"segments": {}, "skin_mm": "x"}, "t.toml")


def _box(rng: np.random.Generator, frames: int, centre: np.ndarray) -> np.ndarray:
    return centre + rng.normal(0, 60, (4, 3))[None] + rng.normal(0, 0.3, (frames, 4, 3))


def test_static_take_gives_coordinates_joint_from_markers_and_prefixes_are_stripped() -> None:
    rng = np.random.default_rng(0)
    upper, lower = _box(rng, 50, np.array([0, 0, 1000.0])), _box(rng, 50, np.array([0, 0, 600.0]))
    knee = np.stack([np.full((50, 3), [-50, 0, 800.0]), np.full((50, 3), [50, 0, 800.0])], axis=1)
    positions = np.concatenate([upper, lower, knee], axis=1)
    names = [f"S:{n}" for n in ("U1", "U2", "U3", "U4", "L1", "L2", "L3", "L4", "KL", "KM")]
    template = Template("t", {"up": ["U1", "U2", "U3", "U4"], "low": ["L1", "L2", "L3", "L4"]},
                        [(("up", "low"), ["KL", "KM"])], 5.0)
    model = fit_template(template, names, positions)
    assert [s.markers for s in model.segments] == [names[:4], names[4:8]]
    joint = model.joints[0]
    segment = model.segments[0]
    # The centre in the upper frame sits where the knee midpoint is relative to the upper markers.
    coords = np.asarray(segment.coordinates)
    world_centroid = upper.mean(axis=(0, 1))
    distance_model = np.linalg.norm(np.asarray(joint.centres[0]) - coords.mean(axis=0))
    assert abs(distance_model - np.linalg.norm([0, 0, 800.0] - world_centroid)) < 2.0
    assert all(abs(s - 5.0) < 1.0 for s in segment.spread)  # static noise and skin, combined
    assert base_name("Derrick:LASI") == "LASI"
    assert SubjectModel.from_json(model.to_json()) == model


def test_a_take_of_another_marker_set_is_refused() -> None:
    template = load_template("rajagopal")
    with pytest.raises(FormulationError, match="three markers of fewer than two segments"):
        fit_template(template, ["A", "B", "C"], np.zeros((5, 3, 3)))


@pytest.mark.skipif(not STATIC.exists(), reason="needs ../shared/data")
def test_cli_fits_the_rajagopal_static_trial(tmp_path: Path) -> None:
    out = tmp_path / "subject.json"
    result = CliRunner().invoke(app, ["model", str(STATIC), "--out", str(out), "--markerset", "rajagopal"])
    assert result.exit_code == 0, result.output
    model = SubjectModel.from_json(out.read_text())
    assert len(model.segments) == 12 and len(model.joints) == 11
    take = read_labeled(STATIC)
    assert {m for s in model.segments for m in s.markers} <= set(take.names)


@pytest.mark.skipif(not STATIC.exists(), reason="needs ../shared/data")
def test_cli_names_the_template_segments_the_take_does_not_show(tmp_path: Path) -> None:
    """CMU 85_02 under plug-in-gait (its pelvis markers named otherwise) lost pelvis, thighs,
    shanks and feet to singles with exit code 0 and no word; its own template loses none."""
    cmu = STATIC.parents[1] / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
    warned = CliRunner().invoke(app, ["model", str(cmu), "--out", str(tmp_path / "a.json"), "--markerset", "plug-in-gait"])
    assert warned.exit_code == 0, warned.output
    assert ("warning: template 'plug-in-gait': 7 of its 13 segments not found in the take (pelvis, l_thigh, r_thigh, "
            "l_shank, r_shank, l_foot, r_foot)") in warned.output
    own = CliRunner().invoke(app, ["model", str(STATIC), "--out", str(tmp_path / "b.json"), "--markerset", "rajagopal"])
    assert own.exit_code == 0 and "segments not found" not in own.output
