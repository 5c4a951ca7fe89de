"""Formulations by name: swapping one is one argument.

``get_formulation("ilp", time_limit=10)`` or an instance; ``describe()`` lists every
formulation with its parameters, defaults and one-line docs (read from the class's
``Attributes:`` docstring section, so the listing cannot drift from the code).
"""

from __future__ import annotations

import dataclasses
import inspect
import re
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import import_module
from typing import Any

from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation, plain

# name -> "module:Class"; imported on first use so one solver's absence breaks only its formulation.
_FORMULATIONS = {
    "lp-l1": "formulations.methods.lp_l1:LpL1",
    "lp-l1-cvxpy": "formulations.methods.lp_l1_cvxpy:LpL1Cvxpy",
    "qp-l2": "formulations.methods.qp_l2:QpL2",
    "ilp": "formulations.methods.ilp:Ilp",
    "dp-sequential": "formulations.methods.dp_sequential:DpSequential",
    "dp-extended": "formulations.methods.dp_extended:DpExtended",
    "nn-hungarian": "formulations.methods.nn_hungarian:NnHungarian",
    "mht": "formulations.methods.mht:Mht",
}


@dataclass(frozen=True)
class Parameter:
    """One parameter of a formulation."""

    name: str
    default: Any
    doc: str


@dataclass(frozen=True)
class Description:
    """A formulation as listed: name, one-line doc, parameters."""

    name: str
    doc: str
    parameters: tuple[Parameter, ...]


def names() -> list[str]:
    """The registered formulations' names, sorted (``markerflow formulations`` lists them)."""
    return sorted(_FORMULATIONS)


def formulation_class(name: str) -> type[Formulation]:
    if name not in _FORMULATIONS:
        raise FormulationError(f"unknown formulation '{name}'; known: {', '.join(names())}")
    module, cls = _FORMULATIONS[name].split(":")
    formulation: type[Formulation] = getattr(import_module(module), cls)
    return formulation


def get_formulation(spec: str | Mapping[str, Any] | Formulation, **parameters: Any) -> Formulation:
    """A formulation instance from a name (with parameters), a table (``{"name": "ilp",
    "time_limit": 10}``, as a ``[formulation]`` TOML table reads) or an instance (returned as is).

    Raises:
        FormulationError: Unknown name or parameter, or a value out of range, named.
    """
    if isinstance(spec, Formulation):
        if parameters:
            raise FormulationError("parameters go with a formulation name, not with an instance")
        return spec
    if isinstance(spec, Mapping):
        table = dict(spec)
        name = table.pop("name", None)
        if not isinstance(name, str):
            raise FormulationError(f"a formulation table needs a 'name' (one of {', '.join(names())}), got {spec!r}")
        return get_formulation(name, **table, **parameters)
    if not isinstance(spec, str):
        raise FormulationError(f"a formulation is a name, a table or a Formulation, got {spec!r}")
    parameters = {key: plain(value) for key, value in parameters.items()}
    cls = formulation_class(spec)
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(parameters) - known)
    if unknown:
        have = f"known: {', '.join(sorted(known))}" if known else "it takes none"
        raise FormulationError(f"formulation '{spec}' has no parameter '{unknown[0]}'; {have}")
    return cls(**parameters)


def describe() -> list[Description]:
    """Every formulation with its parameters and defaults."""
    result = []
    for name in names():
        cls = formulation_class(name)
        docs = _attribute_docs(cls)
        parameters = tuple(Parameter(f.name, _default(f), docs.get(f.name, "")) for f in dataclasses.fields(cls))
        summary = (inspect.getdoc(cls) or "").splitlines()[0]
        result.append(Description(name=name, doc=summary, parameters=parameters))
    return result


def _default(field: dataclasses.Field[Any]) -> Any:
    """A parameter's default (every parameter has one: ``get_formulation(name)`` needs none)."""
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return field.default


def _attribute_docs(cls: type) -> dict[str, str]:
    """``name: text`` entries of the Google-style ``Attributes:`` section."""
    doc = inspect.getdoc(cls) or ""
    section = doc.split("Attributes:", 1)[1] if "Attributes:" in doc else ""
    entries: dict[str, str] = {}
    current = None
    for line in section.splitlines():
        match = re.match(r"\s{4}(\w+)(?: \(.*?\))?:\s*(.*)", line)
        if match:
            current = match.group(1)
            entries[current] = match.group(2)
        elif current and line.startswith(" " * 8):
            entries[current] += " " + line.strip()
        elif line.strip():
            break
    return entries
