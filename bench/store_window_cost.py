"""What counting one finished window costs the job store, by the size of the job's capture document.

A job's row is updated once per window (its count and time). SQLite rewrites a row whole, so
while the document was a column of that row each window paid for rewriting it (a 50 MB
document: 70-75 ms, a 50,000-frame job 282 s where its windows took 59 s); in its own table
it does not. Prints the median of ``--repeats`` counted windows per document size.

    .venv/bin/python bench/store_window_cost.py [--sizes-mb 1 10 50] [--repeats 15]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from sqlalchemy import update

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from service.server.store import store_for  # noqa: E402
from service.server.tables import JobRow  # noqa: E402


def window_cost_ms(size_mb: float, repeats: int) -> float:
    """Median milliseconds of one committed window count on a job with a ``size_mb`` document."""
    with tempfile.TemporaryDirectory() as folder:
        store = store_for(f"sqlite:///{folder}/jobs.db")
        job, _ = store.add("local", "json", b"x" * int(size_mb * 1e6), repeats)
        times = []
        for k in range(repeats):
            began = time.perf_counter()
            with store.session.begin() as session:  # what save_window writes to the job's row
                session.execute(update(JobRow).where(JobRow.id == job.id).values(windows_done=k + 1))
            times.append(time.perf_counter() - began)
        return 1000 * statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--sizes-mb", type=float, nargs="+", default=[1.0, 10.0, 50.0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    for size in args.sizes_mb:
        print(f"document {size:g} MB: {window_cost_ms(size, args.repeats):.2f} ms per counted window", flush=True)


if __name__ == "__main__":
    main()
