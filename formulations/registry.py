"""Formulations by name: swapping one is one argument."""

from __future__ import annotations

import dataclasses
from typing import Any

from formulations.formulation import Formulation
from formulations.lp_l1 import LpL1
from formulations.lp_l1_cvxpy import LpL1Cvxpy

FORMULATIONS: dict[str, type[Formulation]] = {cls.name: cls for cls in (LpL1, LpL1Cvxpy)}


def get_formulation(spec: str | Formulation, **parameters: Any) -> Formulation:
    """A formulation instance from a name (with parameters) or an instance (returned as is).

    Raises:
        ValueError: Unknown name or parameter, naming it and what is known.
    """
    if isinstance(spec, Formulation):
        if parameters:
            raise ValueError("parameters go with a formulation name, not with an instance")
        return spec
    if spec not in FORMULATIONS:
        raise ValueError(f"unknown formulation '{spec}'; known: {', '.join(sorted(FORMULATIONS))}")
    cls = FORMULATIONS[spec]
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(parameters) - known)
    if unknown:
        raise ValueError(f"formulation '{spec}' has no parameter '{unknown[0]}'; known: {', '.join(sorted(known))}")
    return cls(**parameters)
