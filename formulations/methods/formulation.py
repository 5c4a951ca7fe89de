"""The contract every formulation honours: a WindowProblem in, a WindowSolution out."""

from __future__ import annotations

import numbers
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

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
    # Tighter bounds for the parameters of a user's [formulation] table (``check_table_limits``).
    table_limits: ClassVar[dict[str, float]] = {}
    # False for a frame-by-frame baseline: its costs must not see the frames after the one it
    # assigns (the chain then gives it the guide's last step as the expected one).
    look_ahead: ClassVar[bool] = True

    @abstractmethod
    def solve(self, problem: WindowProblem) -> WindowSolution:
        """Integral paths for the window, with their certificate."""


# I and J of Murty's k-best search (``mht``, and the k-best repair of ``lp-l1``): each frame
# keeps up to I * J children. The defaults are 5 and 10; the repair's study reached 30. A
# table a user writes may ask up to 100 (10^4 children a frame: already seconds a window);
# code may ask up to 10^4, where on a small window Murty's enumeration runs out first (an
# exhaustive search); past that only memory grows.
TABLE_BRANCHING, MAX_BRANCHING = 100, 10_000
# xi within the tolerance of 0 or 1 counts as integral; at 0.5 every xi in [0, 1] would, and
# the certificate would call any fractional optimum integral: tolerances lie in (0, 0.5).
MAX_INTEGRALITY_TOLERANCE = 0.5


def plain(value: object) -> object:
    """A numpy scalar as the Python value it holds (``np.int64(5)`` is no ``int``, and a
    formulation's parameters are written to JSON); anything else as is."""
    return value.item() if isinstance(value, np.generic) else value


def check_parameters(
    formulation: Formulation, positive: tuple[str, ...] = (), non_negative: tuple[str, ...] = (),
    optional_positive: tuple[str, ...] = (), flags: tuple[str, ...] = (), integers: tuple[str, ...] = (),
    at_most: dict[str, float] | None = None, below: dict[str, float] | None = None,
) -> None:
    """Raise ``FormulationError`` naming the first parameter out of range.

    ``flags`` must be bools (TOML's ``"no"`` is a non-empty string, true to Python);
    ``integers`` whole numbers; ``at_most`` and ``below`` map names to inclusive and strict
    upper bounds.
    """
    def bad(name: str, value: object, rule: str) -> FormulationError:
        return FormulationError(f"{formulation.name}: parameter '{name}' must be {rule}, got {value!r}")

    upper, strict = at_most or {}, below or {}
    for name in flags:
        if not isinstance(plain(getattr(formulation, name)), bool):
            raise bad(name, getattr(formulation, name), "true or false")
    for name in positive + non_negative + optional_positive:
        value = plain(getattr(formulation, name))
        if value is None and name in optional_positive:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
            raise bad(name, value, "an integer" if name in integers else "a number")
        if name in integers and not isinstance(value, numbers.Integral):
            raise bad(name, value, "an integer")
        if name in non_negative and value < 0:
            raise bad(name, value, ">= 0")
        if name not in non_negative and value <= 0:
            raise bad(name, value, "> 0")
        if name in upper and value > upper[name]:
            raise bad(name, value, f"<= {upper[name]:g}")
        if name in strict and value >= strict[name]:
            raise bad(name, value, f"< {strict[name]:g}")


def check_table_limits(formulation: Formulation) -> None:
    """Raise ``FormulationError`` when a parameter exceeds its ``table_limits`` bound: what a
    user's table may ask, below the hard bound code may (``TABLE_BRANCHING``)."""
    for name, bound in formulation.table_limits.items():
        value = getattr(formulation, name)
        if value is not None and value > bound:
            raise FormulationError(f"{formulation.name}: parameter '{name}' must be <= {bound:g}, got {value!r}")
