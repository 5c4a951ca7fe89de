"""Prometheus metrics read from the store at scrape time.

From the store rather than in-process counters: windows may be solved by Dask workers or
by an earlier run of the server, and the store has them all.
"""

from __future__ import annotations

from prometheus_client import CollectorRegistry
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily, HistogramMetricFamily
from sqlalchemy import case, func, select

from service.server.store import STATES, JobStore
from service.server.tables import JobRow, WindowRow

SOLVE_SECONDS_BUCKETS = (0.001, 0.005, 0.01, 0.05, 0.1, 0.5, 1.0, 5.0, 10.0, 60.0)


class StoreCollector:
    """Jobs by state (gauge), windows solved (counter), window solve time (histogram)."""

    def __init__(self, store: JobStore) -> None:
        self.store = store

    def collect(self):
        jobs = GaugeMetricFamily("markerflow_jobs", "Jobs in the store by state.", labels=["state"])
        for state, count in count_by_state(self.store).items():
            jobs.add_metric([state], count)
        yield jobs
        below, count, seconds = solve_time_histogram(self.store, SOLVE_SECONDS_BUCKETS)
        yield CounterMetricFamily("markerflow_windows_solved", "Windows solved and stored.", value=count)
        buckets = [(repr(b), n) for b, n in zip(SOLVE_SECONDS_BUCKETS, below)] + [("+Inf", count)]
        yield HistogramMetricFamily("markerflow_window_solve_seconds", "Solver time per window.",
                                    buckets=buckets, sum_value=seconds)


def count_by_state(store: JobStore) -> dict[str, int]:
    with store.session() as session:
        counts = dict(session.execute(select(JobRow.state, func.count()).group_by(JobRow.state)).all())
    return {state: int(counts.get(state, 0)) for state in STATES}


def solve_time_histogram(store: JobStore, bounds: tuple[float, ...]) -> tuple[list[int], int, float]:
    """Windows with solve time <= each bound, all windows, and the seconds summed (one query)."""
    columns = [func.coalesce(func.sum(case((WindowRow.solve_seconds <= b, 1), else_=0)), 0) for b in bounds]
    with store.session() as session:
        *below, count, total = session.execute(
            select(*columns, func.count(), func.coalesce(func.sum(WindowRow.solve_seconds), 0.0))
        ).one()
    return [int(n) for n in below], int(count), float(total)


def metrics_registry(store: JobStore) -> CollectorRegistry:
    registry = CollectorRegistry(auto_describe=False)
    registry.register(StoreCollector(store))
    return registry
