"""Labeling with no labeled frame: a subject model identifies the start and acquires late markers."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_subject_model import chain
from typer.testing import CliRunner

from formulations.subject.fit import fit_subject
from service.capture.capture import Capture, LabelingOptions
from service.capture.document import read_capture_document
from service.capture.model_input import check_shared_names, model_names, with_model
from service.cli.app import app
from service.errors import InputError
from service.evaluation.model_start import evaluate_from_model
from service.evaluation.scenario import Scenario
from service.io.formats import write_labeled
from service.io.recording import LabeledTrajectories, Recording
from service.labeling.capture_labeling import CaptureLabeling

FIT = 250


def _take(seed: int = 0, frames: int = 400):
    names, positions, _ = chain(seed, frames=frames)
    return names, positions, fit_subject(names, positions[:FIT]).model


def _cloud(positions: np.ndarray, absent: np.ndarray, seed: int = 0):
    """Shuffled points per frame with 2 ghosts; each point's marker (-1 ghost)."""
    rng = np.random.default_rng(seed)
    frames, markers = [], []
    for f, truth in enumerate(positions):
        keep = np.flatnonzero(~absent[f])
        points = np.concatenate([truth[keep], truth[rng.integers(0, len(truth), 2)] + rng.normal(0, 200, (2, 3))])
        owner = np.concatenate([keep, [-1, -1]])
        order = rng.permutation(len(points))
        frames.append(points[order])
        markers.append(owner[order])
    return frames, markers


def test_held_out_frames_are_labeled_from_the_model_and_a_late_marker_is_acquired() -> None:
    names, positions, model = _take()
    order = [names.index(n) for n in model_names(model)]
    held = positions[FIT:, order]
    absent = np.zeros(held.shape[:2], bool)
    late = 5
    absent[:30, late] = True  # not there when labeling starts
    frames, owner = _cloud(held, absent)
    capture = Capture(model_names(model), np.full((len(order), 3), np.nan), 100.0, points=frames, model=model)
    result, _ = CaptureLabeling(capture, LabelingOptions(window=10)).label()
    took = result.point_index
    right = sum(int(owner[f][took[f, m]] == m) for f in range(len(frames)) for m in range(len(order)) if took[f, m] >= 0)
    visible = int((~absent).sum())
    assert right >= 0.99 * visible
    assert (took[40:, late] >= 0).all() and all(owner[f][took[f, late]] == late for f in range(40, len(frames)))


def test_capture_json_takes_a_model_in_place_of_the_first_frame() -> None:
    chain_names, positions, model = _take(1, frames=300)
    body = {"rate": 100, "model": json.loads(model.to_json()), "points": positions[FIT:FIT + 5].tolist()}
    capture = read_capture_document(json.dumps(body), "c.json").capture()
    assert capture.model == model and capture.names == model_names(model)
    body["first_frame"] = positions[FIT].tolist()
    with pytest.raises(InputError, match="model: give markers and first_frame together"):
        read_capture_document(json.dumps(body), "c.json")
    names = model_names(model)
    labeled = positions[FIT, [chain_names.index(name) for name in names[:2]]]
    body["markers"], body["first_frame"] = names[:2], labeled.tolist()  # partly labeled: kept
    kept = read_capture_document(json.dumps(body), "c.json").capture()
    assert kept.names == names and np.isnan(kept.first_frame[2:]).all()
    np.testing.assert_array_equal(kept.first_frame[:2], labeled)
    assert kept.unnamed_markers == len(names) - 2  # their points are unnamed until the model names them
    del body["first_frame"], body["markers"]
    body["model"]["version"] = 7
    with pytest.raises(InputError, match="version 7 is not supported"):
        read_capture_document(json.dumps(body), "c.json")


def test_bad_spans_other_marker_sets_and_scenario_keys_are_one_line() -> None:
    names, positions, model = _take(2, frames=300)
    capture = Capture(names, positions[0], 100.0, points=list(positions[:10]))
    with pytest.raises(InputError, match=r"--start 9: .* the take has 10, so 0 <= start <= 8"):
        with_model(capture, model, start=9)
    with pytest.raises(InputError, match="only 0 of its 3 markers are in the model"):
        check_shared_names(["X", "Y", "Z"], model, "take.trc")
    with pytest.raises(InputError, match="scenario key 'first_frame' must be one of labeled, model"):
        Scenario.from_dict({"first_frame": "guess"})
    truth = Recording(names, positions[:30], 100.0)
    with pytest.raises(InputError, match="unnamed_markers = 2 with a subject model"):  # was a ValueError past labeling
        evaluate_from_model(truth, Scenario.from_dict({"unnamed_markers": 2}), model)


def test_cli_tracks_a_labeled_file_from_the_model(tmp_path: Path) -> None:
    names, positions, model = _take(3, frames=320)
    take, subject = tmp_path / "take.trc", tmp_path / "subject.json"
    write_labeled(take, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0))
    subject.write_text(model.to_json())
    out = tmp_path / "labeled.csv"
    runner = CliRunner()
    result = runner.invoke(app, ["track", str(take), "--model", str(subject), "--start", str(FIT), "--out", str(out),
                                 "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout.strip().splitlines()[-1])["frames"] == 320 - FIT  # warnings go to stderr
    subject.write_text("{")
    result = runner.invoke(app, ["track", str(take), "--model", str(subject), "--out", str(out)])
    assert result.exit_code == 2 and "subject model is not JSON" in result.output


def test_a_capture_json_whose_markers_the_model_lacks_is_refused() -> None:
    """Another marker set's model named the points its way and the document's markers vanished
    from the result (the job ended done); an upload with such a model was already refused."""
    chain_names, positions, model = _take(1, frames=300)
    names = [f"OTHER{i}" for i in range(4)]
    body = {"rate": 100, "model": json.loads(model.to_json()), "points": positions[FIT:FIT + 5].tolist(),
            "markers": names, "first_frame": positions[FIT, :4].tolist()}
    with pytest.raises(InputError, match=r"^c.json: markers: only 0 of its 4 markers are in the model \(not in it: OTHER0"):
        read_capture_document(json.dumps(body), "c.json")


def test_the_frame_by_frame_reading_of_an_identified_take_acquires_from_the_model_too() -> None:
    """An identified take is read frame by frame as well (``rival_reading``), with the model
    naming late markers there too: a reading that never names them could not be merged in."""
    names, positions, model = _take()
    order = [names.index(n) for n in model_names(model)]
    held = positions[FIT:, order]
    absent = np.zeros(held.shape[:2], bool)
    late = 5
    absent[:30, late] = True
    frames, owner = _cloud(held, absent)
    capture = Capture(model_names(model), np.full((len(order), 3), np.nan), 100.0, points=frames, model=model)
    labeling = CaptureLabeling(capture, LabelingOptions(window=10))
    outcomes = labeling.read_beside("frame-by-frame")
    assert outcomes is not None
    took = labeling.assembled(outcomes, repaired=False).point_index
    right = [owner[f][took[f, late]] == late for f in range(40, len(frames)) if took[f, late] >= 0]
    assert len(right) > 0.9 * (len(frames) - 40) and np.mean(right) > 0.95
