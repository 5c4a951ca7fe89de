"""Prometheus metrics read from the store at scrape time.

From the store rather than in-process counters: windows may be solved by Dask workers or
by an earlier run of the server, and the store has them all.
"""

from __future__ import annotations

from prometheus_client import CollectorRegistry
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily, HistogramMetricFamily

from service.server.store import JobStore

SOLVE_SECONDS_BUCKETS = (0.001, 0.005, 0.01, 0.05, 0.1, 0.5, 1.0, 5.0, 10.0, 60.0)


class StoreCollector:
    """Jobs by state (gauge), windows solved (counter), window solve time (histogram)."""

    def __init__(self, store: JobStore) -> None:
        self.store = store

    def collect(self):
        jobs = GaugeMetricFamily("markerflow_jobs", "Jobs in the store by state.", labels=["state"])
        for state, count in self.store.count_by_state().items():
            jobs.add_metric([state], count)
        yield jobs
        below, count, seconds = self.store.solve_time_histogram(SOLVE_SECONDS_BUCKETS)
        yield CounterMetricFamily("markerflow_windows_solved", "Windows solved and stored.", value=count)
        buckets = [(repr(b), n) for b, n in zip(SOLVE_SECONDS_BUCKETS, below)] + [("+Inf", count)]
        yield HistogramMetricFamily("markerflow_window_solve_seconds", "Solver time per window.",
                                    buckets=buckets, sum_value=seconds)


def metrics_registry(store: JobStore) -> CollectorRegistry:
    registry = CollectorRegistry(auto_describe=False)
    registry.register(StoreCollector(store))
    return registry
