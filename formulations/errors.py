"""What a formulation raises when it cannot take a problem or a parameter value."""


class FormulationError(ValueError):
    """A parameter out of range, or a problem this formulation cannot take.

    The message is one line naming the parameter (or the limit) and the value, e.g.
    "dp-extended: joint state space 2.1e+09 exceeds max_states = 1e+07".
    """


class SolverFailure(RuntimeError):
    """The solver stopped with an error (not a time limit, which is a result with its status):
    no answer for the window exists, and returning one would be silent garbage."""
