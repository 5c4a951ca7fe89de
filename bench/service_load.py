"""Load on the HTTP service over loopback: accepted jobs per second and request latencies.

Starts ``markerflow serve`` in a subprocess on 127.0.0.1 with a temporary SQLite store,
then sends a bounded load from ``--clients`` concurrent clients:

1. ``POST /v1/solve`` of a small one-window capture (labeled while the client waits);
2. ``POST /v1/jobs`` of a small capture (answered once the job is committed; the jobs
   then run in the server's pool, competing for the same cores as the next requests).

Prints requests/second and p50/p99 latency for each. Usage:

    .venv/bin/python bench/service_load.py [--clients 8] [--jobs 400] [--solves 200]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx
import numpy as np

from service.capture.capture import Capture, LabelingOptions
from service.capture.document import CaptureDocument
from service.evaluation.scenario import Scenario
from service.evaluation.scene import generate_scene
from service.evaluation.simulate_cloud import simulate_cloud

REPO = Path(__file__).resolve().parents[1]


def small_capture(frames: int, seed: int) -> Capture:
    truth = generate_scene(n_frames=frames, seed=seed)
    simulated = simulate_cloud(truth, Scenario(noise_mm=1.0, drop_rate=0.05, drop_burst_frames=5,
                                               ghosts_per_frame=1.0, seed=seed))
    return Capture(list(truth.names), simulated.first_frame.positions[0], truth.rate, points=simulated.cloud.points)


def start_server(folder: Path) -> tuple[subprocess.Popen, str]:
    log = folder / "server.log"
    with log.open("w") as out:
        process = subprocess.Popen([sys.executable, "-m", "service.cli", "serve", "--port", "0",
                                    "--db", f"sqlite:///{folder / 'bench.db'}"], cwd=REPO, stdout=out, stderr=out)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        found = re.search(r"Uvicorn running on (http://127\.0\.0\.1:\d+)", log.read_text())
        if found:
            return process, found.group(1)
        time.sleep(0.05)
    process.kill()
    raise SystemExit(f"server did not start:\n{log.read_text()}")


def load(url: str, path: str, body: bytes, requests: int, clients: int, expect: int) -> tuple[float, np.ndarray]:
    """Send ``requests`` POSTs from ``clients`` threads; (wall seconds, per-request latencies)."""
    per_client = [requests // clients + (i < requests % clients) for i in range(clients)]

    def client(count: int) -> list[float]:
        latencies = []
        with httpx.Client(base_url=url, timeout=120, headers={"content-type": "application/json"}) as http:
            for _ in range(count):
                began = time.perf_counter()
                answer = http.post(path, content=body)
                latencies.append(time.perf_counter() - began)
                if answer.status_code != expect:
                    raise SystemExit(f"{path}: {answer.status_code} {answer.text[:200]}")
        return latencies

    began = time.perf_counter()
    with ThreadPoolExecutor(clients) as pool:
        latencies = [t for part in pool.map(client, per_client) for t in part]
    return time.perf_counter() - began, np.array(latencies)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--jobs", type=int, default=400)
    parser.add_argument("--solves", type=int, default=200)
    args = parser.parse_args()
    job_body = CaptureDocument.of(small_capture(30, 1), LabelingOptions(window=10)).model_dump_json().encode()
    solve_body = CaptureDocument.of(small_capture(10, 2), LabelingOptions(window=10)).model_dump_json().encode()
    with tempfile.TemporaryDirectory(prefix="markerflow-bench-") as folder:
        process, url = start_server(Path(folder))
        try:
            httpx.post(f"{url}/v1/solve", content=solve_body, headers={"content-type": "application/json"})  # warm up
            rows = [
                ("POST /v1/solve", len(solve_body), *load(url, "/v1/solve", solve_body, args.solves, args.clients, 200)),
                ("POST /v1/jobs", len(job_body), *load(url, "/v1/jobs", job_body, args.jobs, args.clients, 202)),
            ]
        finally:
            process.kill()
            process.wait()
    print(f"{args.clients} concurrent clients on loopback, SQLite store (WAL, synchronous=FULL)\n")
    print(f"{'request':<16}{'body KiB':>9}{'requests':>10}{'per second':>12}{'p50 ms':>9}{'p99 ms':>9}")
    for name, size, wall, latencies in rows:
        p50, p99 = np.percentile(latencies, [50, 99]) * 1000
        print(f"{name:<16}{size / 1024:>9.1f}{len(latencies):>10}{len(latencies) / wall:>12.1f}{p50:>9.1f}{p99:>9.1f}")


if __name__ == "__main__":
    main()
