"""The contract every formulation honours: a WindowProblem in, a WindowSolution out."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

from formulations.errors import FormulationError
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution


@dataclass(frozen=True)
class Formulation(ABC):
    """Poses and solves one window.

    Subclasses are small frozen dataclasses whose fields are their parameters (with
    defaults, documented under ``Attributes``), and whose ``solve`` returns integral paths
    with their objective evaluated by ``formulations.window.objective.path_cost``, so costs
    compare across formulations. ``lower_bound`` is a proven bound on the optimum (the
    optimum itself for exact methods, -inf when a method proves none); ``integral`` is True
    only when the returned paths are proven optimal. A parameter out of range, or a
    problem the formulation cannot take, raises ``FormulationError`` naming it.
    """

    name: ClassVar[str]
    # False for a frame-by-frame baseline: its costs must not see the frames after the one it
    # assigns (the chain then gives it the guide's last step as the expected one).
    look_ahead: ClassVar[bool] = True

    @abstractmethod
    def solve(self, problem: WindowProblem) -> WindowSolution:
        """Integral paths for the window, with their certificate."""


def check_parameters(
    formulation: Formulation, positive: tuple[str, ...] = (), non_negative: tuple[str, ...] = (),
    optional_positive: tuple[str, ...] = (),
) -> None:
    """Raise ``FormulationError`` naming the first parameter out of range."""
    def bad(name: str, value: object, rule: str) -> FormulationError:
        return FormulationError(f"{formulation.name}: parameter '{name}' must be {rule}, got {value!r}")

    for name in positive + non_negative + optional_positive:
        value = getattr(formulation, name)
        if value is None and name in optional_positive:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
            raise bad(name, value, "a number")
        if name in non_negative and value < 0:
            raise bad(name, value, ">= 0")
        if name not in non_negative and value <= 0:
            raise bad(name, value, "> 0")
