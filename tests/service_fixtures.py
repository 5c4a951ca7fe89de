"""The HTTP service under test: a real uvicorn on a loopback ephemeral port, and captures to send it."""

from __future__ import annotations

import re
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import httpx
import numpy as np
import uvicorn

from service.capture.capture import Capture, LabelingOptions
from service.capture.document import CaptureDocument
from service.evaluation.scenario import Scenario
from service.evaluation.scene import generate_scene
from service.evaluation.simulate_cloud import simulate_cloud
from service.server.app import create_app
from service.server.settings import Settings

REPO = Path(__file__).resolve().parents[1]
SCENARIO = Scenario(noise_mm=1.0, drop_rate=0.1, drop_burst_frames=10, ghosts_per_frame=2.0)


def generated_capture(frames: int, seed: int = 0, **scenario: float) -> Capture:
    """A walking figure's noisy, gappy, ghosted 3D points, frame 0 labeled; ``scenario`` overrides ``SCENARIO``."""
    truth = generate_scene(n_frames=frames, seed=seed)
    simulated = simulate_cloud(truth, Scenario(**{**SCENARIO.__dict__, **scenario, "seed": seed}))
    return Capture(list(truth.names), simulated.first_frame.positions[0], truth.rate, points=simulated.cloud.points)


def document_json(capture: Capture, options: LabelingOptions = LabelingOptions()) -> str:
    return CaptureDocument.of(capture, options).model_dump_json()


@contextmanager
def serving(settings: Settings, token: str | None = None):
    """``create_app(settings)`` under uvicorn in a thread on 127.0.0.1:<free port>; an httpx client to it."""
    server = uvicorn.Server(uvicorn.Config(create_app(settings), host="127.0.0.1", port=0, log_level="warning",
                                           timeout_graceful_shutdown=2))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started:
        assert thread.is_alive() and time.monotonic() < deadline, "server did not start"
        time.sleep(0.02)
    port = server.servers[0].sockets[0].getsockname()[1]
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    try:
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=60, headers=headers) as client:
            yield client
    finally:
        server.should_exit = True
        thread.join(15)


def wait_for(client: httpx.Client, job_id: str, states=("done", "failed", "cancelled"), timeout: float = 60) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        job = client.get(f"/v1/jobs/{job_id}").json()
        if job["state"] in states or time.monotonic() > deadline:
            return job
        time.sleep(0.05)


def nan_array(values) -> np.ndarray:
    """JSON positions (null where occluded) as floats with NaN."""
    return np.array(values, dtype=float)


class ServerProcess:
    """``markerflow serve`` in a subprocess (``python -m service.cli``), for tests that kill it."""

    def __init__(self, db: str, log: Path) -> None:
        self.log = log
        with log.open("w") as out:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "service.cli", "serve", "--port", "0", "--db", db],
                cwd=REPO, stdout=out, stderr=subprocess.STDOUT,
            )
        self.url = self._wait_for_url()

    def _wait_for_url(self) -> str:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            found = re.search(r"Uvicorn running on (http://127\.0\.0\.1:\d+)", self.log.read_text())
            if found:
                return found.group(1)
            assert self.process.poll() is None, self.log.read_text()
            time.sleep(0.05)
        raise AssertionError(f"server did not start: {self.log.read_text()}")

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            self.process.wait(15)
