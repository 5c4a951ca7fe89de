"""Schemathesis over every operation of a served markerflow, on SQLite and on PostgreSQL:
valid and invalid requests, each answer checked against the response schema; exits non-zero on
any 5xx or failed check.

Starts ``markerflow serve`` in a subprocess per store (a temporary SQLite file; a throwaway
PostgreSQL cluster on 127.0.0.1, see ``tests/postgres_cluster.py``, skipped saying why where it
cannot start) and prints per operation the cases sent and their answers by status class.
Hypothesis stops early on an operation whose inputs run out (one without parameters).

    .venv/bin/python bench/schemathesis_run.py [--cases 200] [--store sqlite --store postgresql]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from postgres_cluster import PostgresCluster, PostgresUnavailable  # noqa: E402  (the tests' helpers)
from schema_fuzz import fuzz_failures, fuzz_schema  # noqa: E402
from service_fixtures import ServerProcess  # noqa: E402

# As the test: bodies up to 1 MiB, /v1/solve up to 20 frames, so every case answers quickly.
LIMITS = {"MARKERFLOW_LIMITS__MAX_BODY_BYTES": str(2**20), "MARKERFLOW_LIMITS__MAX_SOLVE_FRAMES": "20"}


def run(store: str, db: str, folder: Path, cases: int) -> int:
    """Fuzz a server on ``db``: prints the table, returns the number of failures."""
    server = ServerProcess(db, folder / f"{store}.log", env=LIMITS)
    try:
        started = time.monotonic()
        tallies = fuzz_schema(server.url, cases)
        seconds = time.monotonic() - started
        alive = server.process.poll() is None
    finally:
        server.stop()
    print(f"\n{store}: {sum(t.cases for t in tallies.values())} cases in {seconds:.0f} s, server alive: {alive}")
    for operation, tally in tallies.items():
        statuses = "  ".join(f"{status} {count}" for status, count in sorted(tally.statuses.items()))
        print(f"  {operation:32s} {tally.cases:5d} cases  {statuses}  failures {len(tally.failures)}")
    failures = fuzz_failures(tallies)
    for failure in failures[:20]:
        print(f"  FAIL {failure}")
    return len(failures) + (not alive)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--cases", type=int, default=200, help="generated cases per operation")
    parser.add_argument("--store", action="append", choices=["sqlite", "postgresql"])
    args = parser.parse_args()
    failed = 0
    with tempfile.TemporaryDirectory(prefix="markerflow-schemathesis-") as folder:
        for store in args.store or ["sqlite", "postgresql"]:
            if store == "sqlite":
                failed += run(store, f"sqlite:///{folder}/jobs.db", Path(folder), args.cases)
                continue
            try:
                cluster = PostgresCluster()
            except PostgresUnavailable as reason:
                print(f"\npostgresql: skipped, {reason}")
                continue
            try:
                failed += run(store, cluster.database(), Path(folder), args.cases)
            finally:
                cluster.stop()
    print(f"\n{failed} failures")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
