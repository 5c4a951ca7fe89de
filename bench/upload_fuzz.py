"""Hostile uploads against a served markerflow: the issue-15 reproducers plus fresh random
mutations of a real C3D, each answered 202 or 4xx by a server that stays up.

Starts ``markerflow serve`` in a subprocess (temporary SQLite store, one job at a time),
uploads ``../shared/reliability/*.c3d`` and ``--count`` mutations (1-4 bytes changed, half in
the header and parameter section) of ``c3d_mocaprecovery_cmu_hdm05_numediart/85_02.c3d`` (every
marker seen in frame 0), and prints the answers by status and message, the server's peak RSS
(VmHWM; reader children excluded) and the time.

    .venv/bin/python bench/upload_fuzz.py [--count 200] [--seed 15]
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from service_fixtures import ServerProcess, fuzz_uploads, upload_fuzz  # noqa: E402  (the tests' helpers)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=15)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="markerflow-fuzz-") as folder:
        server = ServerProcess(f"sqlite:///{folder}/jobs.db", Path(folder) / "server.log",
                               env={"MARKERFLOW_MAX_PARALLEL_JOBS": "1"})
        try:
            started = time.monotonic()
            answers = upload_fuzz(server.url, fuzz_uploads(args.count, args.seed))
            seconds = time.monotonic() - started
            alive, peak = server.process.poll() is None, server.peak_rss_mib()
        finally:
            server.stop()
    kinds = Counter((status, re.sub(r"\b\d+\b", "N", message)[:90]) for status, message in answers.values())
    print(f"{len(answers)} uploads ({args.count} mutations, seed {args.seed}) in {seconds:.1f} s; "
          f"server alive: {alive}; server peak RSS {peak:.0f} MiB")
    for (status, message), n in sorted(kinds.items(), key=lambda item: (item[0][0], -item[1])):
        print(f"{n:>5}  {status}  {message}")
    bad = {label: answer for label, answer in answers.items() if answer[0] != 202 and not 400 <= answer[0] < 500}
    if bad or not alive:
        raise SystemExit(f"FAILED: {bad}")


if __name__ == "__main__":
    main()
