"""Screenshots of the web page: the jobs list and a finished job's page, in headless Chromium.

Starts the service on a loopback port with a temporary SQLite store, submits a few
generated takes (a clean one, a cluttered one whose LP windows go fractional, one
cancelled; and a camera take when ``../shared/data`` has CMU 85_02 and the Pose2Sim rig),
waits for them, then writes ``out/web-list.png``, ``out/web-job.png`` (the cluttered take) and,
with the data, ``out/web-camera-job.png``. Uses Debian's chromium (``.ci/run`` installs it).

    .venv/bin/python bench/web_screenshots.py [--frames 300] [--out out]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import threading
import time
from pathlib import Path

import httpx
from playwright.sync_api import sync_playwright

from service.capture.capture import Capture, LabelingOptions
from service.capture.document import CaptureDocument
from service.evaluation.scenario import Scenario
from service.evaluation.scene import generate_scene
from service.evaluation.simulate_cloud import simulate_cloud
from service.server.app import create_app
from service.server.serving import service_server
from service.server.settings import Settings

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
CMU = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "85_02.c3d"
POSE2SIM = DATA / "multicam2d_pose2sim_demo" / "calibration" / "Calib_qualisys.toml"


def generated(frames: int, seed: int, **scenario: float) -> Capture:
    truth = generate_scene(n_frames=frames, seed=seed)
    simulated = simulate_cloud(truth, Scenario(**{"noise_mm": 1.0, "drop_rate": 0.1, "drop_burst_frames": 10,
                                                  "ghosts_per_frame": 2.0, **scenario, "seed": seed}))
    return Capture(list(truth.names), simulated.first_frame.positions[0], truth.rate, points=simulated.cloud.points)


def camera_take(frames: int) -> Capture | None:
    """CMU 85_02 seen by the Pose2Sim rig's cameras (0.5 px noise, occlusions, clutter), if the data is there."""
    if not (CMU.exists() and POSE2SIM.exists()):
        return None
    from formulations.cameras.rig import Rig
    from service.evaluation.simulate_cameras import place_in_volume, simulate_cameras
    from service.io.calibration import load_pose2sim_toml
    from service.io.formats import read_labeled
    from service.io.recording import Recording

    cameras, truth = load_pose2sim_toml(POSE2SIM, units="mm"), read_labeled(CMU)
    rig = Rig.of(cameras)
    placed = Recording(truth.names[:12], place_in_volume(truth.positions[:frames, :12], rig), truth.rate)
    simulated = simulate_cameras(placed, rig, pixel_noise=0.5, merge_radius_px=3.0, occlusion_rate=0.1,
                                 occlusion_burst_frames=15, clutter_per_camera=2, seed=0)
    first = simulated.first_frame
    return Capture(first.names, first.positions[0], first.rate, cameras=cameras, detections=simulated.detections)


def submit(client: httpx.Client, capture: Capture, options: LabelingOptions) -> str:
    answer = client.post("/v1/jobs", content=CaptureDocument.of(capture, options).model_dump_json(),
                         headers={"content-type": "application/json"})
    answer.raise_for_status()
    return answer.json()["id"]


def wait(client: httpx.Client, job_id: str, timeout: float = 300) -> str:
    deadline = time.monotonic() + timeout
    while (state := client.get(f"/v1/jobs/{job_id}").json()["state"]) in ("queued", "running"):
        if time.monotonic() > deadline:
            raise SystemExit(f"job {job_id} still {state} after {timeout:g} s")
        time.sleep(0.2)
    return state


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args()
    executable = shutil.which("chromium")
    if executable is None:
        raise SystemExit("no chromium on PATH: apt-get install chromium")
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="markerflow-web-") as folder:
        settings = Settings(db=f"sqlite:///{folder}/jobs.db", max_parallel_jobs=2)
        server = service_server(create_app(settings), settings, "127.0.0.1", 0, "warning")
        thread = threading.Thread(target=server.run, daemon=True)
        thread.start()
        while not server.started:
            time.sleep(0.05)
        url = f"http://127.0.0.1:{server.servers[0].sockets[0].getsockname()[1]}"
        try:
            shots = take_screenshots(url, executable, args.frames, args.out)
        finally:
            server.should_exit = True
            thread.join(15)
    for path in shots:
        print(f"wrote {path}")


def take_screenshots(url: str, executable: str, frames: int, out: Path) -> list[Path]:
    with httpx.Client(base_url=url, timeout=120) as client:
        long_take = submit(client, generated(20 * frames, seed=7), LabelingOptions(window=20))
        client.delete(f"/v1/jobs/{long_take}")  # cancelled, to show that state in the list
        cluttered = submit(client, generated(frames // 2, seed=10, noise_mm=6.0, ghosts_per_frame=40.0),
                           LabelingOptions(formulation="lp-l1", window=20))
        clean = submit(client, generated(frames, seed=3), LabelingOptions(window=20))
        cameras = camera_take(frames // 2)
        camera_job = submit(client, cameras, LabelingOptions(window=20)) if cameras is not None else None
        for job in (cluttered, clean, camera_job):
            if job is not None:
                print(f"job {job}: {wait(client, job)}")
    pages = {"web-list.png": "/", "web-job.png": f"/jobs/{cluttered}"}
    if camera_job is not None:
        pages["web-camera-job.png"] = f"/jobs/{camera_job}"
    written = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, headless=True)
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        for name, path in pages.items():
            page.goto(url + path)
            page.wait_for_load_state("networkidle")
            page.screenshot(path=out / name, full_page=True)
            written.append(out / name)
        browser.close()
    return written


if __name__ == "__main__":
    main()
