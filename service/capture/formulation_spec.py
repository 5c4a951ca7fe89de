"""A formulation from what a user writes: a name, or a ``[formulation]`` TOML table (or an instance).

    [formulation]
    name = "ilp"
    time_limit = 10.0
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation, check_table_limits
from formulations.methods.registry import get_formulation
from service.errors import InputError
from service.io.toml_file import read_toml


def formulation_from_table(table: dict[str, Any], where: str) -> Formulation:
    """The formulation a ``[formulation]`` table names, with its parameters.

    Raises:
        InputError: No name, unknown name or parameter, or a value out of range (or past its
            ``table_limits``: a table asks for at most what runs in reasonable time).
    """
    parameters = dict(table)
    name = parameters.pop("name", None)
    if not isinstance(name, str):
        raise InputError(f"{where}: [formulation] needs name = \"...\" (e.g. \"lp-l1\")")
    try:
        formulation = get_formulation(name, **parameters)
        check_table_limits(formulation)
        return formulation
    except (FormulationError, TypeError) as error:
        raise InputError(f"{where}: {error}") from None


def resolve_formulation(spec: str | dict[str, Any] | Formulation, where: str = "formulation") -> Formulation:
    """The formulation of a name, a ``[formulation]`` table or an instance (returned as is).

    Raises:
        InputError: As ``formulation_from_table``.
    """
    if isinstance(spec, Formulation):
        return spec
    return formulation_from_table({"name": spec} if isinstance(spec, str) else spec, where)


def formulation_from_spec(spec: str) -> Formulation:
    """``spec`` is a formulation name, or the path of a TOML file with a ``[formulation]`` table."""
    if not spec.lower().endswith(".toml"):
        return resolve_formulation(spec, "--formulation")
    return formulation_from_table(formulation_table(Path(spec)), spec)


def formulation_table(path: Path) -> dict[str, Any]:
    """The ``[formulation]`` table of a TOML preset.

    Raises:
        InputError: Unreadable file, bad TOML, or no ``[formulation]`` table.
    """
    data = read_toml(path)
    if not isinstance(data.get("formulation"), dict):
        raise InputError(f"{path}: no [formulation] table")
    return data["formulation"]
