"""The frame-by-frame reading (and the ``mht`` reading when asked) in a process of its own,
beside the window reading's second pass.

A doubtful take is read four times: two window passes, then the frame-by-frame reading and its
own second pass (``rival_reading``; on the real 03_rolling 18 + 21 s of windows, then 12 + 10 s).
The frame-by-frame reading needs nothing of the window passes, so on a machine with a second
core it runs in a child process while the window reading's second pass runs here, and the two
meet at the merge. The child is a fresh interpreter (``python -m service.labeling.rival_child``),
not a fork: multiprocessing forbids a job's daemonic worker children, and a fork of a threaded
server is unsafe; a plain subprocess works the same under the CLI, a job's worker and a Dask
worker. Its start-up (about 1.5 s of imports here) is paid back only on a take whose first pass
took ``BESIDE_MIN_SECONDS`` or more (half that with the ``mht`` reading too, ``runs_beside``);
a smaller take is read here after the second pass, as it always was. Either way the labels
are the same (``tests/test_rival_process.py``).

The ``mht`` reading (``hypothesis_reading``, asked for by ``LabelingOptions.mht_reading``) needs
nothing of the others either, and runs in a second child started with the first: three
processes on two cores, so the readings share them instead of the ``mht`` reading waiting
for the merge of the frame-by-frame one.

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
from collections.abc import Callable, Iterator
from pathlib import Path
from types import TracebackType

from service.capture.capture import Capture, LabelingOptions
from service.labeling.loop import Progress
from service.labeling.outcome import WindowOutcome
from service.labeling.second_pass import Stop, second_pass_runs
from service.labeling.stats import DOUBTFUL_WARNING

READINGS = ("frame-by-frame", "mht")  # what a child reads: ``CaptureLabeling.read_beside``
# Doubtful share of the first pass so far from which the readings start beside it: half the
# share a second pass needs (``second_pass_runs``), as a take's first windows are often its
# surest (03_rolling from 562: 1.1 % after 16 of 93 windows, 2.1 % after 38, 3.1 % in all);
# a reading started for a take that ends less doubtful is ended unread (``EarlyStart.taken``),
# so this bar moves only when the readings start, never what they read.
EARLY_DOUBT = DOUBTFUL_WARNING / 2
BESIDE_MIN_SECONDS = 5.0  # first-pass seconds from which a child's ~1.5 s start-up is worth paying
POLL_SECONDS = 0.05  # how often the parent looks at its child (stop latency)


def runs_beside(first_pass_seconds: float, readings: int = 1) -> bool:
    """Whether ``readings`` readings of a take whose first pass took ``first_pass_seconds`` run
    in child processes: a second core to run on, and a take large enough. Each reading is two
    passes of its own, so the work they take off this process grows with their number (the
    ``mht`` reading's passes cost more than a window pass): with the ``mht`` reading too the
    bar halves: the real racing take (first pass under 5 s), read here after the windows, took
    31.9 / 33.4 s with ``--mht-reading``, beside 24.2 / 22.2 s (17.5 / 17.6 s without the
    reading; alternated, 2026-12-06), the same labels."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)  # not on macOS
    return cores >= 2 and first_pass_seconds * readings >= BESIDE_MIN_SECONDS


class RivalBeside:
    """A reading of ``capture`` (one of ``READINGS``) running in a child process; ``read`` waits
    for it. A context manager: leaving it ends the child and removes its files."""

    def __init__(self, capture: Capture, options: LabelingOptions, reading: str = READINGS[0]) -> None:
        self.reading = reading
        self._folder = tempfile.TemporaryDirectory(prefix="markerflow-rival-")
        folder = Path(self._folder.name)
        self._answer = folder / "windows.pickle"
        (folder / "capture.pickle").write_bytes(pickle.dumps((capture, options), protocol=pickle.HIGHEST_PROTOCOL))
        self._errors = (folder / "stderr.txt").open("w+")
        self._process = subprocess.Popen(
            [sys.executable, "-m", "service.labeling.rival_child", str(folder / "capture.pickle"), str(self._answer),
             str(os.getpid()), reading],
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
            raise RuntimeError(f"the {self.reading} reading's process failed (exit {self._process.returncode}): {last}")
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
    """Starts the readings beside during the first pass, as soon as that pass looks long
    enough (``runs_beside`` of its seconds so far per window times its ``windows``) and its
    windows so far are doubtful (``EARLY_DOUBT``): they then run beside the rest of the first
    pass too. On 03_rolling from 562 the reading beside is the longer: started once 5 s of the
    first pass had gone and its share had passed a second pass's bar, it kept the window
    reading waiting 3.5 s at the end of its second pass. ``taken`` hands them over when the
    whole first pass is doubtful enough for a second pass (``second_pass_runs``), and ends
    them otherwise."""

    def __init__(self, capture: Capture, options: LabelingOptions, readings: tuple[str, ...] = READINGS[:1],
                 windows: int = 1) -> None:
        self._capture, self._options, self._readings, self._windows = capture, options, readings, windows
        self._seen: list[WindowOutcome] = []
        self._children = Beside({})

    def watched(self, windows: Iterator[WindowOutcome]) -> Iterator[WindowOutcome]:
        """``windows``, each looked at (``EarlyStart``) as it finishes."""
        for outcome in windows:
            self._seen.append(outcome)
            if not self._children.children and runs_beside(self._projected_seconds(), len(self._readings)) \
                    and second_pass_runs(self._seen, bar=EARLY_DOUBT):
                self._children = started(self._capture, self._options, self._readings)
            yield outcome

    def _projected_seconds(self) -> float:
        """The first pass's seconds, projected from its windows so far."""
        seconds = sum(o.stats.total_seconds for o in self._seen)
        return seconds * max(self._windows, len(self._seen)) / len(self._seen)

    def taken(self, wanted: bool) -> Beside:
        """The readings started early, if ``wanted`` (else they are ended); none if none started."""
        children, self._children, self._seen = self._children, Beside({}), []
        if not wanted:
            children.__exit__(None, None, None)
            return Beside({})
        return children


class Beside:
    """The readings running in child processes, by name (``READINGS``); a context manager that
    ends them all on leaving."""

    def __init__(self, children: dict[str, RivalBeside]) -> None:
        self.children = children

    def read(self, reading: str, here: Callable[[str, Progress | None, Stop | None], list[WindowOutcome] | None],
             progress: Progress | None = None, stop: Stop | None = None) -> list[WindowOutcome] | None:
        """``reading``'s windows from its child (``RivalBeside.read``), or read ``here`` when it has none."""
        child = self.children.get(reading)
        return here(reading, progress, stop) if child is None else child.read(progress, stop)

    def __enter__(self) -> Beside:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None) -> None:
        for child in self.children.values():
            child.__exit__(kind, error, trace)


def started(capture: Capture, options: LabelingOptions, readings: tuple[str, ...]) -> Beside:
    """A child process for each of ``readings``."""
    return Beside({reading: RivalBeside(capture, options, reading) for reading in readings})
