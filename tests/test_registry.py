"""Formulations are swapped by one argument: name, instance, or TOML table."""

import dataclasses
import re
from pathlib import Path

import pytest

from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation
from formulations.methods.lp_l1 import LpL1
from formulations.methods.registry import describe, formulation_class, get_formulation, names
from service.capture.formulation_spec import formulation_from_spec
from service.errors import InputError
from service.evaluation.scenario import Scenario

README = Path(__file__).resolve().parents[1] / "README.md"


def test_every_formulation_lists_its_parameters_with_docs_and_defaults():
    for description in describe():
        assert description.doc
        fields = {f.name for f in dataclasses.fields(get_formulation(description.name))}
        assert {p.name for p in description.parameters} == fields
        assert all(p.doc for p in description.parameters), description.name


def test_name_with_parameters_builds_the_instance():
    chosen = get_formulation("lp-l1", decompose=False, pricing_successors=2)
    assert chosen == LpL1(decompose=False, pricing_successors=2)
    assert get_formulation(chosen) is chosen


@pytest.mark.parametrize("name,parameters,named", [
    ("nope", {}, "nope"),
    ("lp-l1", {"pricing_sucessors": 2}, "pricing_sucessors"),
    ("lp-l1", {"pricing_successors": -1}, "pricing_successors"),
    ("lp-l1", {"integrality_tolerance": 0}, "integrality_tolerance"),
    ("lp-l1", {"time_limit": -5.0}, "time_limit"),
    ("lp-l1-cvxpy", {"solver": "HIGSH"}, "solver"),
])
def test_bad_choices_name_what_is_wrong(name, parameters, named):
    with pytest.raises(FormulationError, match=named):
        get_formulation(name, **parameters)


def test_toml_table_and_scenario_table_choose_the_same_formulation(tmp_path):
    preset = tmp_path / "whole.toml"
    preset.write_text('[formulation]\nname = "lp-l1"\ndecompose = false\n')
    assert formulation_from_spec(str(preset)) == LpL1(decompose=False)
    scenario = Scenario.from_dict({"formulation": {"name": "lp-l1", "decompose": False}})
    assert (scenario.formulation, scenario.formulation_parameters) == ("lp-l1", {"decompose": False})


def test_toml_errors_are_one_line_input_errors(tmp_path):
    nameless = tmp_path / "nameless.toml"
    nameless.write_text("[formulation]\ndecompose = false\n")
    with pytest.raises(InputError, match="needs name"):
        formulation_from_spec(str(nameless))
    with pytest.raises(InputError, match="bogus"):
        formulation_from_spec(str(tmp_path / "bogus.toml"))


def test_every_registered_name_resolves_to_a_formulation_of_that_name():
    assert [d.name for d in describe()] == names() and names()
    for name in names():
        cls = formulation_class(name)
        assert issubclass(cls, Formulation) and cls.name == name
        assert get_formulation(name) == cls()


def test_the_readme_table_lists_exactly_the_registered_formulations():
    section = README.read_text().split("## Formulations", 1)[1].split("\n## ", 1)[0]
    documented = re.findall(r"^\| `([\w-]+)`", section, flags=re.MULTILINE)
    assert sorted(documented) == names()


def test_parameter_messages_say_what_is_wanted() -> None:
    with pytest.raises(FormulationError, match="has no parameter 'foo'; it takes none"):
        get_formulation("nn-hungarian", foo=1)
    with pytest.raises(FormulationError, match="'hypotheses' must be an integer, got True"):
        get_formulation("mht", hypotheses=True)


def test_a_table_builds_what_name_and_parameters_build():
    """``LabelingOptions`` takes a table; ``get_formulation`` answered one with "unhashable type"."""
    assert get_formulation({"name": "ilp", "time_limit": 10}) == get_formulation("ilp", time_limit=10)
    with pytest.raises(FormulationError, match="needs a 'name'"):
        get_formulation({"time_limit": 10})
    with pytest.raises(FormulationError, match="a name, a table or a Formulation, got 3"):
        get_formulation(3)  # type: ignore[arg-type]


def test_numpy_scalars_are_the_numbers_they_hold():
    """A notebook's ``np.int64(5)`` was refused as "must be an integer, got np.int64(5)"."""
    import numpy as np

    from formulations.methods.ilp import Ilp
    from service.capture.capture import LabelingOptions

    mht = get_formulation("mht", hypotheses=np.int64(5), noise=np.float32(2.0))
    assert mht == get_formulation("mht", hypotheses=5, noise=2.0) and type(mht.hypotheses) is int
    assert Ilp(time_limit=np.int64(10)).time_limit == 10
    options = LabelingOptions(window=np.int32(10), layout_weight=np.float32(1.0), second_pass=np.bool_(False))
    assert (options.window, options.layout_weight, options.second_pass) == (10, 1.0, False)
    assert type(options.second_pass) is bool and type(options.window) is int
