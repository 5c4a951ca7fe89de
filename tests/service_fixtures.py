"""The HTTP service under test: a real uvicorn on a loopback ephemeral port, and captures to send it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import httpx
import numpy as np

from service.capture.capture import Capture, LabelingOptions
from service.capture.document import CaptureDocument
from service.evaluation.scenario import Scenario
from service.evaluation.scene import generate_scene
from service.evaluation.simulate_cloud import simulate_cloud
from service.server.app import create_app
from service.server.serving import service_server
from service.server.settings import Settings

REPO = Path(__file__).resolve().parents[1]
RELIABILITY = REPO.parent / "shared" / "reliability"  # one-byte reproducers of issue 15 (see its README)
FUZZ_C3D = REPO.parent / "shared" / "data" / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
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
    server = service_server(create_app(settings), settings, "127.0.0.1", 0, "warning")
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
    """``markerflow serve`` in a subprocess (``python -m service.cli``), for tests that kill it;
    ``env`` adds ``MARKERFLOW_*`` settings."""

    def __init__(self, db: str, log: Path, env: dict[str, str] | None = None) -> None:
        self.log = log
        with log.open("w") as out:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "service.cli", "serve", "--port", "0", "--db", db],
                cwd=REPO, stdout=out, stderr=subprocess.STDOUT, env={**os.environ, **(env or {})},
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

    def peak_rss_mib(self) -> float:
        """The server process's peak resident memory so far (VmHWM; its reader children not included)."""
        status = Path(f"/proc/{self.process.pid}/status").read_text()
        peak = re.search(r"VmHWM:\s+(\d+) kB", status)
        assert peak is not None, status
        return int(peak.group(1)) / 1024


def resumed_result(db: str, log: Path, job_id: str, timeout: float = 120) -> tuple[dict, int]:
    """A new server on the store ``db`` resumes the job: its JSON result once done, and the server's pid."""
    server = ServerProcess(db, log)
    try:
        with httpx.Client(base_url=server.url, timeout=30) as client:
            assert wait_for(client, job_id, timeout=timeout)["state"] == "done"
            return client.get(f"/v1/jobs/{job_id}/result").json(), server.process.pid
    finally:
        server.stop()


def mutations(data: bytes, count: int, seed: int) -> list[tuple[str, bytes]]:
    """``count`` copies of ``data`` with 1 to 4 random bytes changed, half of them inside the
    header and parameter section (where a reader is steered), half anywhere."""
    rng = np.random.default_rng(seed)
    parameters_end = (data[0] - 1 + data[(data[0] - 1) * 512 + 2]) * 512
    mutated = []
    for i in range(count):
        copy = bytearray(data)
        end = parameters_end if i % 2 == 0 else len(data)
        offsets = rng.integers(0, end, size=1 if i % 3 else rng.integers(2, 5))
        for offset in offsets:
            copy[offset] = int(rng.integers(0, 256))
        mutated.append((",".join(f"{o}={copy[o]:#04x}" for o in offsets), bytes(copy)))
    return mutated


def upload_fuzz(url: str, uploads: list[tuple[str, str, bytes]]) -> dict[str, tuple[int, str]]:
    """POST each ``(label, filename, content)`` to ``/v1/jobs``: label -> (status, message); 0 for no answer."""
    answers = {}
    with httpx.Client(base_url=url, timeout=120) as client:
        for label, filename, content in uploads:
            try:
                answer = client.post("/v1/jobs", files={"file": (filename, content)}, data={"window": "50"})
                answers[label] = (answer.status_code, answer.json().get("message", ""))
            except (httpx.HTTPError, ValueError) as error:
                answers[label] = (0, f"{type(error).__name__}: {error}")
    return answers


def fuzz_uploads(count: int, seed: int) -> list[tuple[str, str, bytes]]:
    """The issue's three C3D reproducers, then ``count`` fresh mutations of ``FUZZ_C3D``."""
    reproducers = [(path.name, path.name, path.read_bytes()) for path in sorted(RELIABILITY.glob("*.c3d"))]
    return reproducers + [(label, "take.c3d", data) for label, data in mutations(FUZZ_C3D.read_bytes(), count, seed)]
