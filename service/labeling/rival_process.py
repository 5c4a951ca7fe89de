"""The frame-by-frame reading in a process of its own, beside the window reading's second pass.

A doubtful take is read four times: two window passes, then the frame-by-frame reading and its
own second pass (``rival_reading``; on the real 03_rolling 18 + 21 s of windows, then 12 + 10 s).
The frame-by-frame reading needs nothing of the window passes, so on a machine with a second
core it runs in a child process while the window reading's second pass runs here, and the two
meet at the merge. The child is a fresh interpreter (``python -m service.labeling.rival_child``),
not a fork: multiprocessing forbids a job's daemonic worker children, and a fork of a threaded
server is unsafe; a plain subprocess works the same under the CLI, a job's worker and a Dask
worker. Its start-up (about 1.5 s of imports here) is paid back only on a take whose first pass
took ``BESIDE_MIN_SECONDS`` or more; a smaller take is read here after the second pass, as it
always was. Either way the labels are the same (``tests/test_rival_process.py``).

The capture and options go to the child in a pickle file; it prints ``k n`` after each window
(its progress) and pickles its windows to a second file. Pickle is safe here: both files are
this process's own, in a private temporary directory. The child exits when this process is gone.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType

from service.capture.capture import Capture, LabelingOptions
from service.labeling.loop import Progress
from service.labeling.outcome import WindowOutcome
from service.labeling.second_pass import Stop, second_pass_runs

BESIDE_MIN_SECONDS = 5.0  # first-pass seconds from which a child's ~1.5 s start-up is worth paying
POLL_SECONDS = 0.05  # how often the parent looks at its child (stop latency)


def runs_beside(first_pass_seconds: float) -> bool:
    """Whether the frame-by-frame reading of a take whose first pass took ``first_pass_seconds``
    runs in a child process: a second core to run on, and a take large enough."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)  # not on macOS
    return cores >= 2 and first_pass_seconds >= BESIDE_MIN_SECONDS


class RivalBeside:
    """The frame-by-frame reading of ``capture`` running in a child process; ``read`` waits for
    it. A context manager: leaving it ends the child and removes its files."""

    def __init__(self, capture: Capture, options: LabelingOptions) -> None:
        self._folder = tempfile.TemporaryDirectory(prefix="markerflow-rival-")
        folder = Path(self._folder.name)
        self._answer = folder / "windows.pickle"
        (folder / "capture.pickle").write_bytes(pickle.dumps((capture, options), protocol=pickle.HIGHEST_PROTOCOL))
        self._errors = (folder / "stderr.txt").open("w+")
        self._process = subprocess.Popen(
            [sys.executable, "-m", "service.labeling.rival_child", str(folder / "capture.pickle"), str(self._answer),
             str(os.getpid())],
            stdout=subprocess.PIPE, stderr=self._errors, text=True, cwd=Path(__file__).resolve().parents[2])
        self._done = (0, 0)  # the child's last progress (windows done, windows)
        self._follower = threading.Thread(target=self._follow, daemon=True)
        self._follower.start()

    def _follow(self) -> None:
        assert self._process.stdout is not None
        for line in self._process.stdout:
            k, n = (int(v) for v in line.split())
            self._done = (k, n)

    def read(self, progress: Progress | None = None, stop: Stop | None = None) -> list[WindowOutcome] | None:
        """The child's windows, once it is done; None when ``stop`` asked to abandon them.

        Raises:
            RuntimeError: The child failed (its last line of error output said why).
        """
        reported = (0, 0)
        while self._process.poll() is None:
            if stop is not None and stop():
                return None
            reported = self._reported(progress, reported)
            time.sleep(POLL_SECONDS)
        self._follower.join()  # its output ends with the process: the last progress is in
        self._reported(progress, reported)
        if self._process.returncode != 0:
            self._errors.seek(0)
            last = (self._errors.read().strip().splitlines() or ["no message"])[-1]
            raise RuntimeError(f"the frame-by-frame reading's process failed (exit {self._process.returncode}): {last}")
        windows: list[WindowOutcome] = pickle.loads(self._answer.read_bytes())
        return windows

    def _reported(self, progress: Progress | None, reported: tuple[int, int]) -> tuple[int, int]:
        """The child's progress passed on if it moved since ``reported``; what was passed on."""
        if progress is None or self._done == reported or not self._done[1]:
            return reported
        progress(*self._done)
        return self._done

    @property
    def ended(self) -> bool:
        """The child has exited (done, failed or killed)."""
        return self._process.poll() is not None

    def __enter__(self) -> RivalBeside:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None) -> None:
        if self._process.poll() is None:
            self._process.kill()
        self._process.wait()
        self._errors.close()
        self._folder.cleanup()


class EarlyStart:
    """Starts the reading beside during the first pass, once that pass has taken
    ``BESIDE_MIN_SECONDS`` and its windows so far are doubtful enough for a second pass
    (``second_pass_runs``): it then runs beside the rest of the first pass too (03_rolling:
    otherwise the window reading's second pass waits 4-5 s for it at the end). ``taken``
    hands it over when the whole first pass is doubtful, and ends it otherwise."""

    def __init__(self, capture: Capture, options: LabelingOptions) -> None:
        self._capture, self._options = capture, options
        self._seen: list[WindowOutcome] = []
        self._child: RivalBeside | None = None

    def watched(self, windows: Iterator[WindowOutcome]) -> Iterator[WindowOutcome]:
        """``windows``, each looked at (``EarlyStart``) as it finishes."""
        for outcome in windows:
            self._seen.append(outcome)
            if self._child is None and runs_beside(sum(o.stats.total_seconds for o in self._seen)) \
                    and second_pass_runs(self._seen):
                self._child = RivalBeside(self._capture, self._options)
            yield outcome

    def taken(self, wanted: bool) -> RivalBeside | None:
        """The reading started early, if ``wanted`` (else it is ended); None if none started."""
        child, self._child, self._seen = self._child, None, []
        if child is not None and not wanted:
            child.__exit__(None, None, None)
            return None
        return child
