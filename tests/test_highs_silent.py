"""The HiGHS backend writes nothing to the process's stdout: `track --json` and `eval --json`
print one JSON line there, and highspy 1.16 printed its licence banner on construction.

HiGHS prints that banner once per process, so the check runs in a fresh interpreter.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
# min x0 + 2 x1 subject to x0 + x1 >= 1 over [0, 1]^2: x = (1, 0), cost 1.
SOLVE = """
import numpy as np, scipy.sparse as sp
from formulations.solvers import create_backend
from formulations.solvers.base import LinearModel
backend = create_backend("highs")
backend.set_model(LinearModel(
    cost=np.array([1.0, 2.0]), matrix=sp.csr_matrix([[1.0, 1.0]]),
    row_lower=np.array([1.0]), row_upper=np.array([np.inf]),
    col_lower=np.zeros(2), col_upper=np.ones(2), integer=np.array([{integer}, {integer}]),
))
result = backend.solve()
assert abs(result.objective - 1.0) < 1e-9, result
"""


@pytest.mark.parametrize("integer", [False, True])
def test_construction_and_solve_print_nothing(integer: bool):
    run = subprocess.run([sys.executable, "-c", SOLVE.format(integer=integer)],
                         cwd=REPO, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout == "" and run.stderr == ""


CVXPY_SOLVE = """
import cvxpy as cp
from formulations.solvers.quiet import stdout_to_stderr
x = cp.Variable(nonneg=True)
with stdout_to_stderr():  # as lp-l1-cvxpy solves: cvxpy constructs its own Highs
    cp.Problem(cp.Minimize(x + 1)).solve(solver="HIGHS")
print("result", round(x.value + 1, 6))
"""


def test_what_cvxpy_s_highs_prints_goes_to_stderr_and_the_result_to_stdout():
    run = subprocess.run([sys.executable, "-c", CVXPY_SOLVE], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout == "result 1.0\n"


# HiGHS keeps one thread scheduler per process. Once another HiGHS (cvxpy's for `lp-l1-cvxpy`,
# or a user's own highspy) started it with two threads, a run asking for one thread was
# refused; with output off nothing said so, and every window came back "Not Set" with all its
# markers occluded.
ANOTHER_HIGHS_FIRST = """
import highspy
other = highspy.Highs()
other.setOptionValue("output_flag", False)
other.setOptionValue("threads", 2)
other.addVar(0, 1)
assert other.run() == highspy.HighsStatus.kOk
"""


@pytest.mark.parametrize("integer", [False, True])
def test_a_scheduler_started_by_another_highs_does_not_stop_ours(integer: bool):
    run = subprocess.run([sys.executable, "-c", ANOTHER_HIGHS_FIRST + SOLVE.format(integer=integer)],
                         cwd=REPO, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr  # SOLVE asserts the optimum: "Not Set" has none
