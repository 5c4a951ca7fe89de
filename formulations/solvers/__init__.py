"""Solver backends: a small contract (pass a model, solve, add columns, re-solve).

Backends are imported lazily so that ``formulations`` loads without every solver.
Options are set through the backend's typed setters (``set_timeout``, ...).
"""

from __future__ import annotations

from importlib import import_module

from formulations.solvers.base import LinearModel, SolverBackend, SolveResult

_BACKENDS = {
    "highs": "formulations.solvers.highs:HighsBackend",
    "clarabel": "formulations.solvers.clarabel_lp:ClarabelBackend",  # interior point only: central duals
}


def create_backend(name: str = "highs") -> SolverBackend:
    """A fresh backend instance by name (imports the solver on first use), solver defaults set."""
    if name not in _BACKENDS:
        raise ValueError(f"unknown solver backend '{name}'; known: {', '.join(sorted(_BACKENDS))}")
    module, cls = _BACKENDS[name].split(":")
    backend: type[SolverBackend] = getattr(import_module(module), cls)
    return backend()


__all__ = ["LinearModel", "SolveResult", "SolverBackend", "create_backend"]
