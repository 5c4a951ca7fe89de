"""``POST /v1/models`` over real HTTP: a subject model fitted from an uploaded labeled take is
the one ``markerflow model`` writes, groups the synthetic skeleton's markers right, and, sent
back as ``"model"`` of a ``POST /v1/jobs`` capture, labels held-out frames; bad input is a
one-line 4xx; with tokens configured a caller without one gets 401."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from service_fixtures import serving, wait_for
from test_subject_model import LIMB, chain
from typer.testing import CliRunner

from formulations.subject.model import SubjectModel
from service.cli.app import app
from service.io.formats import write_labeled
from service.io.recording import LabeledTrajectories
from service.server.settings import Limits, Settings

FIT, HELD = 250, 40  # frames the model is fitted on, then frames labeled from it
SECRET = "models-token-0123456789"
TEMPLATE = """name = "chain"
[segments]
S0 = ["S0M0", "S0M1", "S0M2", "S0M3"]
S1 = ["S1M0", "S1M1", "S1M2", "S1M3"]
S2 = ["S2M0", "S2M1", "S2M2", "S2M3"]
[[joints]]
segments = ["S0", "S1"]
centre = ["J0"]
[[joints]]
segments = ["S1", "S2"]
centre = ["J1"]
"""


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    db = tmp_path_factory.mktemp("models") / "jobs.db"
    with serving(Settings(db=f"sqlite:///{db}", max_parallel_jobs=1)) as client:
        yield client


@pytest.fixture(scope="module")
def take():
    names, positions, _ = chain(5, frames=FIT + HELD)
    return names, positions


def _write(path: Path, names: list[str], positions: np.ndarray) -> Path:
    write_labeled(path, LabeledTrajectories(names, positions, np.isnan(positions).any(axis=2), 100.0))
    return path


def _fit(client, path: Path, **fields: str):
    with path.open("rb") as upload:
        return client.post("/v1/models", files={"file": (path.name, upload)}, data=fields)


def _refused(answer, status: int, start: str) -> str:
    assert answer.status_code == status, answer.text
    message = answer.json()["message"]
    assert message.startswith(start) and "\n" not in message, message
    return message


def test_fitted_model_is_the_cli_s_and_labels_a_job(client, take, tmp_path: Path) -> None:
    names, positions = take
    c3d = _write(tmp_path / "rom.c3d", names, positions[:FIT])
    answer = _fit(client, c3d)
    assert answer.status_code == 200, answer.text
    model = SubjectModel.from_json(answer.text)
    assert [s.markers for s in model.segments] == [[f"S{s}M{m}" for m in range(4)] for s in range(4)]
    assert len(model.joints) == 3
    written = tmp_path / "subject.json"
    assert CliRunner().invoke(app, ["model", str(c3d), "--out", str(written)]).exit_code == 0
    assert answer.text == written.read_text()
    csv = _write(tmp_path / "rom.csv", names, positions[:FIT])  # markerflow's own table, same model
    assert _fit(client, csv).text == answer.text

    order = [names.index(n) for n in (m for s in model.segments for m in s.markers)]
    truth = positions[FIT:, order]
    rng = np.random.default_rng(0)
    points = [np.concatenate([frame[rng.permutation(len(frame))], rng.uniform(0, 1500, (1, 3))]).tolist()
              for frame in truth]
    document = {"rate": 100, "model": answer.json(), "points": points, "window": 10}
    job = client.post("/v1/jobs", content=json.dumps(document), headers={"content-type": "application/json"})
    assert job.status_code == 202, job.text
    assert wait_for(client, job.json()["id"])["state"] == "done"
    result = client.get(f"/v1/jobs/{job.json()['id']}/result").json()
    assert result["markers"] == [names[i] for i in order]
    labeled = np.array(result["positions"], dtype=float)
    right = np.linalg.norm(labeled - truth, axis=2) < 1e-6
    assert right.mean() >= 0.99


def test_a_partly_labeled_first_frame_is_kept_and_the_model_names_the_rest(client, take, tmp_path: Path) -> None:
    names, positions = take
    model = _fit(client, _write(tmp_path / "rom.c3d", names, positions[:FIT])).json()
    truth = positions[FIT:]
    labeled = names[::2]  # the lab named every other marker of frame 0
    points = [frame[np.random.default_rng(1).permutation(len(frame))].tolist() for frame in truth]
    document = {"rate": 100, "model": model, "points": points, "window": 10, "markers": labeled,
                "first_frame": truth[0, ::2].tolist()}
    job = client.post("/v1/jobs", content=json.dumps(document), headers={"content-type": "application/json"})
    assert job.status_code == 202, job.text
    assert job.json()["warnings"] == []
    assert wait_for(client, job.json()["id"])["state"] == "done"
    result = client.get(f"/v1/jobs/{job.json()['id']}/result").json()
    order = [names.index(name) for name in result["markers"]]
    right = np.linalg.norm(np.array(result["positions"], dtype=float) - truth[:, order], axis=2) < 1e-6
    assert right.mean() >= 0.99
    misplaced = truth[0].copy()
    misplaced[names.index("S2M1")] += [0.0, 0.0, 80.0]  # labeled where the model has no marker
    off = {**document, "markers": names, "first_frame": misplaced.tolist()}
    warned = client.post("/v1/jobs", content=json.dumps(off), headers={"content-type": "application/json"})
    assert warned.status_code == 202, warned.text
    [warning] = warned.json()["warnings"]
    assert warning.startswith("warning: the labels of frame 0 do not fit 1 of the model's segments")
    done = wait_for(client, warned.json()["id"])
    assert done["state"] == "done" and warning in done["warnings"]  # kept with the result, not only in the 202
    nose = truth[:, names.index("S0M0")] + [0.0, 60.0, 0.0]  # a marker the model lacks: labeled, it becomes a single
    with_nose = {**document, "markers": [*names[:4], "NOSE"], "first_frame": [*truth[0, :4].tolist(), nose[0].tolist()],
                 "points": [[*frame, nose[f].tolist()] for f, frame in enumerate(points)]}
    job = client.post("/v1/jobs", content=json.dumps(with_nose), headers={"content-type": "application/json"})
    assert job.status_code == 202, job.text
    assert wait_for(client, job.json()["id"])["state"] == "done"
    result = client.get(f"/v1/jobs/{job.json()['id']}/result").json()
    nose_track = np.array(result["positions"], dtype=float)[:, result["markers"].index("NOSE")]
    assert (np.linalg.norm(nose_track - nose, axis=1) < 1e-6).mean() >= 0.99
    half = {key: value for key, value in document.items() if key != "first_frame"}
    _refused(client.post("/v1/jobs", content=json.dumps(half), headers={"content-type": "application/json"}),
             422, "model: give markers and first_frame together")


def test_an_upload_with_a_model_keeps_its_partly_labeled_frame_0(client, take, tmp_path: Path) -> None:
    names, positions = take
    model = _fit(client, _write(tmp_path / "rom.c3d", names, positions[:FIT])).text
    held = positions[FIT:].copy()
    held[:8, 3] = np.nan  # S0M3 absent from frame 0 and the seven after it
    upload = _write(tmp_path / "held.c3d", names, held).read_bytes()
    refused = client.post("/v1/jobs", files={"file": ("held.c3d", upload)}, data={"window": "10"})
    said = _refused(refused, 422, "file: marker 'S0M3' has no position in the first frame (1 of ")
    assert "start=8 labels from the frame with the most" in said and "subject model as 'model'" in said
    job = client.post("/v1/jobs", files={"file": ("held.c3d", upload), "model": ("subject.json", model)},
                      data={"window": "10"})
    assert job.status_code == 202, job.text
    assert wait_for(client, job.json()["id"])["state"] == "done"
    result = client.get(f"/v1/jobs/{job.json()['id']}/result").json()
    order = [names.index(name) for name in result["markers"]]
    right = np.linalg.norm(np.array(result["positions"], dtype=float) - held[:, order], axis=2) < 1e-3
    seen = np.isfinite(held[:, order]).all(axis=2)
    assert right[seen].mean() >= 0.99
    assert right[10:, result["markers"].index("S0M3")].all()  # named by the model once back
    other = client.post("/v1/jobs", files={"file": ("held.c3d", upload), "model": ("subject.json", "[1, 2]")})
    _refused(other, 422, "model: a subject model is a JSON object")


def test_an_upload_of_unlabeled_trajectories_is_named_by_the_model_as_the_cli_names_it(client, take, tmp_path) -> None:
    """The service refused it ("only 0 of its 12 markers are in the model (not in it: *0, *1 ...)")."""
    names, positions = take
    model = tmp_path / "subject.json"
    model.write_text(_fit(client, _write(tmp_path / "rom.c3d", names, positions[:FIT])).text)
    unlabeled = [f"*{i}" for i in range(len(names))]
    upload = _write(tmp_path / "unlabeled.c3d", unlabeled, positions[FIT:])
    job = client.post("/v1/jobs", files={"file": ("unlabeled.c3d", upload.read_bytes()),
                                         "model": ("subject.json", model.read_text())}, data={"window": "10"})
    assert job.status_code == 202, job.text
    assert wait_for(client, job.json()["id"])["state"] == "done"
    served = client.get(f"/v1/jobs/{job.json()['id']}/result").json()
    run = CliRunner().invoke(app, ["track", str(upload), "--model", str(model), "--window", "10",
                                   "--out", str(tmp_path / "cli.csv")])
    assert run.exit_code == 0, run.output
    as_csv = client.get(f"/v1/jobs/{job.json()['id']}/result", params={"format": "csv"}).content
    assert as_csv == (tmp_path / "cli.csv").read_bytes()
    order = [names.index(name) for name in served["markers"]]
    right = np.linalg.norm(np.array(served["positions"], dtype=float) - positions[FIT:, order], axis=2) < 1e-3
    assert right.mean() >= 0.99


def test_static_take_needs_a_template(client, tmp_path: Path) -> None:
    names, still, centres = chain(6, segments=3, frames=60, motion=0.0)
    positions = np.concatenate([still, np.stack(centres, axis=1)], axis=1)
    static = _write(tmp_path / "static.trc", [*names, "J0", "J1"], positions)
    _refused(_fit(client, static), 422, "file: static.trc: too static to separate segments: markers S0M0, S0M1")
    answer = _fit(client, static, template=TEMPLATE)
    assert answer.status_code == 200, answer.text
    model = SubjectModel.from_json(answer.text)
    assert [s.name for s in model.segments] == ["S0", "S1", "S2"] and len(model.joints) == 2
    [limb] = model.limbs  # S1 between its two joints, whose centres the template puts at J0 and J1
    assert limb.segment == "S1" and abs(limb.length - LIMB) < 3.0
    with static.open("rb") as upload:  # the template as a file part, not a text field
        as_file = client.post("/v1/models", files={"file": (static.name, upload), "template": ("chain.toml", TEMPLATE)})
    assert as_file.text == answer.text
    _refused(_fit(client, static, markerset="cmu-41"), 422,
             "file: static.trc: only 0 of its 14 markers are in marker set 'cmu-41' (not in it: S0M0")
    _refused(_fit(client, static, template="[segments]\nS0 = 3\n"), 422, "template: [segments] must map")
    _refused(_fit(client, static, template="segments = ["), 422, "template: not valid TOML")


def test_bad_uploads_are_one_line(client, take, tmp_path: Path) -> None:
    names, positions = take
    short = _write(tmp_path / "short.trc", names, positions[:10])
    _refused(_fit(client, short), 422, "file: short.trc: only 10 frames; a subject model needs at least 20")
    broken = tmp_path / "broken.c3d"
    broken.write_bytes(b"\x02P" + bytes(600))
    _refused(_fit(client, broken), 422, "file: broken.c3d: ")
    empty = _write(tmp_path / "empty.trc", names, np.full((30, len(names), 3), np.nan))
    _refused(_fit(client, empty), 422, "file: empty.trc: no marker has a position in any frame; upload a labeled take")
    notes = tmp_path / "notes.json"
    notes.write_text("{}")
    _refused(_fit(client, notes), 422, "file: notes.json is not a .c3d, .trc or .csv file")
    take_file = _write(tmp_path / "take.trc", names, positions[:FIT])
    _refused(_fit(client, take_file, markerset="../../etc/x.toml"), 422, "markerset: unknown marker set")
    _refused(_fit(client, take_file, window="20"), 422, "window: unknown form field")
    no_take = client.post("/v1/models", files={"template": ("chain.toml", TEMPLATE.encode())})
    _refused(no_take, 422, "file: upload a labeled .c3d, .trc or .csv take in the form field 'file'")
    _refused(client.post("/v1/models", content=b"{}", headers={"content-type": "application/json"}), 415,
             "content-type: send multipart/form-data, not application/json")


def test_tokens_and_the_memory_bound(take, tmp_path: Path) -> None:
    names, positions = take
    long = _write(tmp_path / "long.trc", names, np.concatenate([positions] * 12))  # 3480 frames
    limits = Limits(reader_memory_bytes=48 * 2**20)  # the fit would need about 54 MiB
    settings = Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}", tokens={"alice": SECRET}, limits=limits)
    with serving(settings) as anonymous:
        _refused(_fit(anonymous, long), 401, "a bearer token is required")
        anonymous.headers["Authorization"] = f"Bearer {SECRET}"
        _refused(_fit(anonymous, long), 422,
                 "file: long.trc: fitting 3480 frames x 16 markers needs about 54 MiB, over the limit of 48 MiB")


def test_a_model_with_start_and_end_labels_that_span_as_track_does(client, take, tmp_path) -> None:
    """Refused before ("over HTTP a subject model labels the whole file"); now the span's first
    frame keeps its labels and the model names the rest, as ``track --model --keep-labels``."""
    names, positions = take
    model = tmp_path / "subject.json"
    model.write_text(_fit(client, _write(tmp_path / "rom.c3d", names, positions[:FIT])).text)
    whole = positions.copy()
    whole[FIT : FIT + 5, 2] = np.nan  # S0M2 absent at the start: the model names it once back
    upload = _write(tmp_path / "whole.c3d", names, whole)
    span = {"window": "10", "start": str(FIT), "end": str(FIT + HELD)}
    job = client.post("/v1/jobs", files={"file": ("whole.c3d", upload.read_bytes()),
                                         "model": ("subject.json", model.read_text())}, data=span)
    assert job.status_code == 202, job.text
    assert wait_for(client, job.json()["id"])["state"] == "done"
    as_csv = client.get(f"/v1/jobs/{job.json()['id']}/result", params={"format": "csv"}).content
    run = CliRunner().invoke(app, ["track", str(upload), "--model", str(model), "--keep-labels", "--window", "10",
                                   "--start", str(FIT), "--end", str(FIT + HELD), "--out", str(tmp_path / "cli.csv")])
    assert run.exit_code == 0, run.output
    assert as_csv == (tmp_path / "cli.csv").read_bytes()
    rows = as_csv.decode().splitlines()
    assert len(rows) == 1 + HELD and rows[1].startswith(f"{FIT + 1},")  # numbered as the file's frames
    past = client.post("/v1/jobs", files={"file": ("whole.c3d", upload.read_bytes()),
                                          "model": ("subject.json", model.read_text())}, data={"start": "9999"})
    _refused(past, 422, "start=9999: frames are counted from 0")
