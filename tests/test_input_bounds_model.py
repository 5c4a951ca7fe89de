"""Subject model files that are binary, carry non-finite numbers or a negative radius: one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from formulations.errors import FormulationError
from formulations.subject.model import Joint, Limb, Segment, SingleMarker, SubjectModel
from service.capture.model_input import check_shared_names, read_model
from service.errors import InputError


def _model() -> dict:
    coordinates = [[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 120.0, 0.0], [0.0, 0.0, 90.0]]
    segments = [Segment(name, [f"{name}{i}" for i in range(4)], coordinates, [1.0] * 4) for name in ("A", "B")]
    joints = [Joint("AB", ("A", "B"), ([0.0, 0.0, 200.0], [0.0, 0.0, -50.0]), 2.0)]
    model = SubjectModel(segments, joints, [Limb("A", ("AB", "AB"), 0.0)], [SingleMarker("S", ["A"], [150.0], [3.0])])
    return json.loads(model.to_json())


def _write(tmp_path: Path, data: dict) -> Path:
    path = tmp_path / "model.json"
    path.write_text(json.dumps(data))
    return path


def test_a_good_model_loads(tmp_path):
    assert read_model(_write(tmp_path, _model())).marker_radius == 7.0


@pytest.mark.parametrize(("edit", "match"), [
    (lambda d: d["segments"][0]["coordinates"][0].__setitem__(0, float("nan")), "segment 'A'.*coordinates"),
    (lambda d: d["segments"][1]["coordinates"][2].__setitem__(1, float("inf")), "segment 'B'.*coordinates"),
    (lambda d: d["joints"][0]["centres"][1].__setitem__(2, float("nan")), "joint 'AB'.*centres"),
    (lambda d: d.__setitem__("marker_radius", -1.0), "marker_radius"),
    (lambda d: d.__setitem__("marker_radius", float("nan")), "marker_radius"),
    (lambda d: d["singles"][0]["distances"].__setitem__(0, float("nan")), "single marker 'S'"),
    (lambda d: d["limbs"][0].__setitem__("length", float("inf")), "limb"),
    # these were an SVD that did not converge, an AxisError, a KeyError, or silently bad gates:
    (lambda d: d["segments"][0]["spread"].__setitem__(1, float("nan")), r"segment 'A': spread must be finite numbers >= 0"),
    (lambda d: d["segments"][0]["spread"].__setitem__(1, -5.0), r"segment 'A': spread must be finite numbers >= 0"),
    (lambda d: d["segments"][1].update(markers=[], coordinates=[], spread=[]), "segment 'B' has no markers"),
    (lambda d: d["segments"][1]["spread"].pop(), "segment 'B': spread has 3 values for 4 markers"),
    (lambda d: d["singles"][0].__setitem__("segments", ["nosuch"]), "single marker 'S': segment 'nosuch' is not in"),
    (lambda d: d["singles"][0]["sd"].__setitem__(0, -1.0), "single marker 'S': sd must be"),
    (lambda d: d["joints"][0].__setitem__("rms", float("nan")), "joint 'AB': rms must be"),
    (lambda d: d["segments"][0].pop("spread"), r"a segment lacks 'spread' \(it holds name, markers, coordinates"),
    (lambda d: d["segments"][1]["markers"].__setitem__(0, "A0"), "marker 'A0' is on two segments"),
    # these were accepted, then an IndexError in the labeler, minutes per frame, or a skeleton no body has:
    (lambda d: d["segments"][0]["coordinates"][1].__setitem__(0, 1e300), "segment 'A': coordinates must be within"),
    (lambda d: d["segments"][0]["spread"].__setitem__(0, 1000.0), "segment 'A': spread must be within 100 mm"),
    (lambda d: d["joints"][0].__setitem__("segments", ["A", "A"]), "joint 'AB' joins segment 'A' to itself"),
    (lambda d: d["joints"].append({**d["joints"][0], "name": "BA"}), "joint 'BA' closes a loop"),
    (lambda d: d["limbs"][0].__setitem__("joints", ["AB", "nosuch"]), "joint 'nosuch' is not in the model"),
    (lambda d: d["limbs"][0].__setitem__("length", -5.0), "limb of segment 'A': length must be >= 0"),
    (lambda d: d["joints"][0].__setitem__("rest", [[2.0, 0, 0], [0, 1, 0], [0, 0, 1]]), "rest is not a rotation"),
    (lambda d: d.__setitem__("marker_radius", "7"), "marker_radius must be a number"),
    (lambda d: d.__setitem__("colour", "red"), "unknown field 'colour'"),
])
def test_bad_numbers_are_named(tmp_path, edit, match):
    data = _model()
    edit(data)
    with pytest.raises(InputError, match=match) as error:
        read_model(_write(tmp_path, data))
    assert "\n" not in str(error.value)


def test_from_json_refuses_nan_coordinates():
    data = _model()
    data["segments"][0]["coordinates"][1][1] = float("nan")
    with pytest.raises(FormulationError, match="finite"):
        SubjectModel.from_json(json.dumps(data))


def test_binary_file_is_not_a_model(tmp_path):
    path = tmp_path / "take.c3d"
    path.write_bytes(b"\x02P\xff\xfe\x00\x01" * 50)
    with pytest.raises(InputError, match="not a text file") as error:
        read_model(path)
    assert "\n" not in str(error.value)


def test_a_take_of_the_model_s_markers_in_another_case_is_told_so():
    """85_02 ("Male:LFWT") against a model of 135_02 ("male:LFWT") read as "only 0 of 41 markers"."""
    model = SubjectModel.from_json(json.dumps(_model()))
    with pytest.raises(InputError, match=r"only 0 of its 8 markers are in the model .*; 8 differ from the model's "
                                         r"only in upper/lower case\)"):
        check_shared_names([f"{s.lower()}{i}" for s in "AB" for i in range(4)], model, "take.c3d")
    check_shared_names(["*0", "*1", "A0"], model, "take.c3d")  # unlabeled trajectories are no marker set
