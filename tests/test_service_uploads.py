"""An uploaded take's result is written as ``markerflow track`` writes it, over real HTTP:
a C3D keeps the input's analog channels, events and parameters, and every format the
input's frame numbering. The service used to write the labels alone, from frame 1 at 0 s."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest
from service_fixtures import serving, wait_for

from service.capture.capture import LabelingOptions
from service.capture.from_recording import capture_from_recording, capture_from_span
from service.io.formats import read_labeled, write_labeled
from service.labeling.absent_markers import in_order, with_absent
from service.labeling.capture_labeling import CaptureLabeling
from service.server.settings import Settings

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
VICON = DATA / "c3d_ezc3d_testfiles" / "Vicon.c3d"  # 38 analog channels, events, subjects
RUN = DATA / "mocap_opensim" / "rajagopal_motion_capture_run.trc"  # starts at Frame# 23, 0.23 s


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    db = tmp_path_factory.mktemp("uploads") / "jobs.db"
    with serving(Settings(db=f"sqlite:///{db}")) as client:
        yield client


def _uploaded(client, path: Path) -> str:
    with path.open("rb") as upload:
        answer = client.post("/v1/jobs", files={"file": (path.name, upload)})
    assert answer.status_code == 202, answer.text
    job = wait_for(client, answer.json()["id"], timeout=120)
    assert job["state"] == "done", job
    return job["id"]


def _library(path: Path, out: Path) -> None:
    """What ``markerflow track PATH --out OUT`` writes (default options, from frame 0)."""
    recording = read_labeled(path)
    labels, _ = CaptureLabeling(capture_from_recording(recording), LabelingOptions()).label()
    write_labeled(out, labels, recording.source)


def test_a_c3d_result_keeps_the_uploads_analog_channels_and_groups(client, tmp_path):
    job = _uploaded(client, VICON)
    served = client.get(f"/v1/jobs/{job}/result", params={"format": "c3d"}).content
    _library(VICON, tmp_path / "library.c3d")
    assert served == (tmp_path / "library.c3d").read_bytes()
    (tmp_path / "served.c3d").write_bytes(served)
    before, after = ezc3d.c3d(str(VICON)), ezc3d.c3d(str(tmp_path / "served.c3d"))
    assert {"EVENT", "SUBJECTS", "TRIAL"} <= set(after["parameters"])
    channels = before["data"]["analogs"].shape[1]
    assert channels == 38
    np.testing.assert_allclose(after["data"]["analogs"][0, :channels], before["data"]["analogs"][0], atol=1e-4)


def test_a_table_result_keeps_the_uploads_frame_numbers_and_times(client, tmp_path):
    job = _uploaded(client, RUN)
    rows = client.get(f"/v1/jobs/{job}/result", params={"format": "csv"}).text.splitlines()
    frame, time = rows[1].split(",")[:2]
    assert int(frame) == 23 and float(time) == pytest.approx(0.23)
    _library(RUN, tmp_path / "library.csv")
    assert rows == (tmp_path / "library.csv").read_text().splitlines()


def test_a_done_job_says_what_the_cli_warns_of(client, tmp_path):
    """A TRC in mm whose header says m: the job was "done", 100 % windows integral and 0 %
    doubtful, with 99 % of the labels missing; the CLI warned, the job said nothing. Such a
    take is now refused before labeling (markers 100 m apart), on both paths; a body in cm
    whose header says mm is labeled, and the job says what the CLI warns of."""
    lines = (DATA / "mocap_opensim" / "gait2354_subject01_walk1.trc").read_text().splitlines()
    header = lines[2].split("\t")
    header[4] = "m"
    (tmp_path / "metres.trc").write_text("\n".join([*lines[:2], "\t".join(header), *lines[3:]]) + "\n")
    with (tmp_path / "metres.trc").open("rb") as upload:
        refused = client.post("/v1/jobs", files={"file": ("metres.trc", upload)})
    assert refused.status_code == 422 and "the take's length unit is wrong" in refused.json()["message"], refused.text
    rows = [row.split("\t") for row in lines[5:]]
    shrunk = ["\t".join(row[:2] + [f"{float(v) / 10:.6f}" if v.strip() else v for v in row[2:]]) for row in rows]
    (tmp_path / "cm.trc").write_text("\n".join([*lines[:5], *shrunk]) + "\n")
    job = _uploaded(client, tmp_path / "cm.trc")
    warnings = client.get(f"/v1/jobs/{job}").json()["warnings"]
    assert any("not look human-sized" in line for line in warnings), warnings


def test_start_relabels_a_take_whose_first_frame_lacks_markers(client, tmp_path):
    """A real take lacking markers in frame 0 was refused unless a subject model came with it;
    ``start`` relabels it from its own labels there, as ``track --start`` does."""
    racing = DATA / "c3d_kineticstoolkit" / "kinematics_racing_full.c3d"
    refused = client.post("/v1/jobs", files={"file": (racing.name, racing.read_bytes())})
    assert refused.status_code == 422 and "start=17 labels from" in refused.json()["message"]
    past = client.post("/v1/jobs", files={"file": (racing.name, racing.read_bytes())}, data={"start": "17", "end": "9000"})
    assert past.status_code == 422 and past.json()["message"].startswith("start=17 end=9000: frames are counted from 0")
    answer = client.post("/v1/jobs", files={"file": (racing.name, racing.read_bytes())},
                         data={"start": "17", "end": "120"})
    assert answer.status_code == 202, answer.text
    job = wait_for(client, answer.json()["id"], timeout=120)
    assert job["state"] == "done", job
    # as track says it: the markers absent at the start, numbered as the file's frames
    assert any(line.startswith("warning: 6 markers absent at frame 17, not labeled") for line in job["warnings"]), job
    served = client.get(f"/v1/jobs/{job['id']}/result", params={"format": "c3d"}).content
    recording = read_labeled(racing)
    capture, absent = capture_from_span(recording, 17, 120)
    labels, _ = CaptureLabeling(capture, LabelingOptions()).label()
    whole = in_order(with_absent(labels, absent), recording.names)
    write_labeled(tmp_path / "library.c3d", whole, recording.source, 17)
    assert absent and served == (tmp_path / "library.c3d").read_bytes()


def test_a_csv_markerflow_wrote_is_an_upload_too(client, tmp_path):
    """The CLI relabels its own CSV; the service refused it."""
    _library(RUN, tmp_path / "first.csv")
    job = _uploaded(client, tmp_path / "first.csv")
    rows = client.get(f"/v1/jobs/{job}/result", params={"format": "csv"}).text.splitlines()
    _library(tmp_path / "first.csv", tmp_path / "again.csv")
    assert rows == (tmp_path / "again.csv").read_text().splitlines() and rows[1].startswith("23,")
