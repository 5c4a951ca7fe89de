"""The child process of ``rival_process``: a reading of a pickled capture (frame-by-frame or ``mht``).

    python -m service.labeling.rival_child CAPTURE.pickle WINDOWS.pickle PARENT_PID READING

It prints ``k n`` after each window, pickles its windows to the second file, and exits when
its parent is gone (a killed job, Ctrl-C): nobody would read its windows. A module of its own,
so that ``capture_labeling`` -> ``rival_process`` imports nothing back.
"""

from __future__ import annotations

import os
import pickle
import sys
import threading
import time
from pathlib import Path

from service.labeling.capture_labeling import CaptureLabeling

PARENT_POLL_SECONDS = 0.5  # how often the child checks that its parent is still there


def _exit_with_parent(parent: int) -> None:
    """End the child once its parent is gone (killed job, Ctrl-C): nobody will read its windows."""
    while True:
        time.sleep(PARENT_POLL_SECONDS)
        if os.getppid() != parent:
            os._exit(1)


def _main(capture_file: str, answer_file: str, parent: str, reading: str) -> None:
    threading.Thread(target=_exit_with_parent, args=(int(parent),), daemon=True).start()
    capture, options = pickle.loads(Path(capture_file).read_bytes())
    labeling = CaptureLabeling(capture, options)
    windows = labeling.read_beside(reading, lambda k, n: print(k, n, flush=True))
    Path(answer_file).write_bytes(pickle.dumps(windows, protocol=pickle.HIGHEST_PROTOCOL))


if __name__ == "__main__":
    _main(*sys.argv[1:5])
