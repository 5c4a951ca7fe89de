"""Solver backends: a small contract (pass a model, solve, add columns, re-solve).

Backends are imported lazily so that ``formulations`` loads without every solver.
"""

from __future__ import annotations

from importlib import import_module

from formulations.solvers.base import LinearModel, SolverBackend, SolveResult

_BACKENDS = {"highs": "formulations.solvers.highs:HighsBackend"}


def create_backend(name: str = "highs", **options: object) -> SolverBackend:
    """A fresh backend instance by name (imports the solver on first use).

    Args:
        name: Backend name.
        **options: Solver options passed through unchanged (e.g. HiGHS option names).
    """
    if name not in _BACKENDS:
        raise ValueError(f"unknown solver backend '{name}'; known: {', '.join(sorted(_BACKENDS))}")
    module, cls = _BACKENDS[name].split(":")
    return getattr(import_module(module), cls)(**options)


__all__ = ["LinearModel", "SolveResult", "SolverBackend", "create_backend"]
