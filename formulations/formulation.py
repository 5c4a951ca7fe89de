"""The contract every formulation honours: a WindowProblem in, a WindowSolution out."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

from formulations.solution import WindowSolution
from formulations.window import WindowProblem


class Formulation(ABC):
    """Poses and solves one window.

    Subclasses are small frozen dataclasses whose fields are their parameters (with
    defaults, documented under ``Attributes``), and whose ``solve`` returns integral paths
    with their objective evaluated by ``formulations.objective.path_cost``, so costs
    compare across formulations. ``lower_bound`` is a proven bound on the optimum (the
    optimum itself for exact methods, -inf when a method proves none); ``integral`` is True
    only when the returned paths are proven optimal. A parameter out of range, or a
    problem the formulation cannot take, raises ``FormulationError`` naming it.
    """

    name: ClassVar[str]

    @abstractmethod
    def solve(self, problem: WindowProblem) -> WindowSolution:
        """Integral paths for the window, with their certificate."""
