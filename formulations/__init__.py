"""The mathematics of markerflow: window problems, their formulations, markers and cameras.

Pure functions and small dataclasses over numpy arrays; never imports ``service``.

    from formulations import WindowProblem, WindowSolution, Formulation, get_formulation

    solution = get_formulation("lp-l1").solve(problem)   # problem: a WindowProblem
    solution.path, solution.cost, solution.lower_bound, solution.gap
"""

from formulations.errors import FormulationError
from formulations.methods.formulation import Formulation
from formulations.methods.registry import describe, get_formulation, names
from formulations.window.build import build_window
from formulations.window.candidates import WindowCandidates
from formulations.window.costs import ArcCostWeights
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution

__all__ = [
    "ArcCostWeights", "Formulation", "FormulationError", "WindowCandidates", "WindowProblem", "WindowSolution",
    "build_window", "describe", "get_formulation", "names",
]
