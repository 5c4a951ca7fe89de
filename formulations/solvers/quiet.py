"""Solver output kept off stdout, where the CLI prints its results (``--json``).

highspy >= 1.16 prints its licence banner when a ``Highs`` is constructed, before any
option can be set. Our own backend sets the option first (``highs._SilentHighs``), but
cvxpy constructs its ``Highs`` itself; around such a solve the process's stdout file
descriptor points at stderr, so whatever the C++ side prints is still shown, never lost,
and never mixed into a result. A lock keeps two threads from swapping the descriptor at
once (the second would restore the first's redirection).
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_SWAP = threading.Lock()


@contextmanager
def stdout_to_stderr() -> Iterator[None]:
    """Within the block, writes to file descriptor 1 (C or Python) go to descriptor 2."""
    with _SWAP:
        sys.stdout.flush()
        saved = os.dup(1)
        try:
            os.dup2(2, 1)
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
