"""The HiGHS backend solves whatever HiGHS ran before it in the process.

HiGHS keeps one thread scheduler per process. Once another HiGHS (cvxpy's for `lp-l1-cvxpy`,
or a user's own highspy) started it with two threads, a run asking for one thread is refused;
with output off nothing said so, and every window came back "Not Set" with all its markers
occluded. The scheduler is process-wide, so each check runs in a fresh interpreter.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
# A HiGHS of someone else's starts the scheduler with 2 threads; then ours solves
# min x0 + 2 x1 subject to x0 + x1 >= 1 over [0, 1]^2: x = (1, 0), cost 1.
SOLVE_AFTER_ANOTHER = """
import highspy, numpy as np, scipy.sparse as sp
from formulations.solvers import create_backend
from formulations.solvers.base import LinearModel
other = highspy.Highs()
other.setOptionValue("output_flag", False)
other.setOptionValue("threads", 2)
other.addVar(0, 1)
assert other.run() == highspy.HighsStatus.kOk
backend = create_backend("highs")
backend.set_model(LinearModel(
    cost=np.array([1.0, 2.0]), matrix=sp.csr_matrix([[1.0, 1.0]]),
    row_lower=np.array([1.0]), row_upper=np.array([np.inf]),
    col_lower=np.zeros(2), col_upper=np.ones(2), integer=np.array([{integer}, {integer}]),
))
result = backend.solve()
print(result.status, round(result.objective, 9))
"""


@pytest.mark.parametrize("integer", [False, True])
def test_a_scheduler_started_by_another_highs_does_not_stop_ours(integer: bool):
    run = subprocess.run([sys.executable, "-c", SOLVE_AFTER_ANOTHER.format(integer=integer)],
                         cwd=REPO, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[-1].split() == ["Optimal", "1.0"]  # after the other HiGHS's banner
