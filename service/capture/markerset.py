"""Marker-set templates (``configs/markersets/*.toml``): by name or by file."""

from __future__ import annotations

from pathlib import Path

from formulations.errors import FormulationError
from formulations.subject.template import Template
from service.errors import InputError
from service.io.toml_file import read_toml

MARKERSETS = Path(__file__).resolve().parents[2] / "configs" / "markersets"


def shipped() -> list[str]:
    """The names of the templates shipped in ``configs/markersets``."""
    return sorted(p.stem for p in MARKERSETS.glob("*.toml"))


def load_template(spec: str) -> Template:
    """The template named ``spec`` (a shipped name) or read from the .toml file ``spec``.

    Raises:
        InputError: Unknown name, unreadable file, bad TOML or a bad key (one line).
    """
    path = Path(spec) if spec.endswith(".toml") else MARKERSETS / f"{spec}.toml"
    if not spec.endswith(".toml") and spec not in shipped():
        raise InputError(f"unknown marker set {spec!r} (shipped: {', '.join(shipped())}; or give a .toml file)")
    data = read_toml(path)
    try:
        return Template.from_dict(data, path.name)
    except FormulationError as error:
        raise InputError(str(error)) from None
