"""A C3D copy that gains unlabeled ``*N`` points keeps the input's point descriptions and
stays a C3D past 255 points. ezc3d blanked every description when the new points had none,
and a file already in LABELS2 got a LABELS2 longer than 255, which ezc3d wrote and then
could not read ("cannot write (None)" after the whole labeling). Read back with ezc3d.
(Past 255 points in all, ezc3d's own writer drops the descriptions.)"""

from __future__ import annotations

import struct
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from service.errors import InputError
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, SourceFile

FRAMES = 6


def _input(path: Path, markers: int) -> Path:
    rng = np.random.default_rng(markers)
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = np.array([100.0])
    c3d["parameters"]["POINT"]["LABELS"]["value"] = [f"M{i}" for i in range(markers)]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c3d.add_parameter("POINT", "DESCRIPTIONS", [f"plate {i}" for i in range(min(markers, 255))])
    points = np.ones((4, markers, FRAMES))
    points[:3] = rng.uniform(-1000, 1000, (3, markers, FRAMES))
    c3d["data"]["points"] = points
    c3d.write(str(path))
    return path


def _entries(c3d: ezc3d.c3d, stem: str) -> list[str]:
    point = c3d["parameters"]["POINT"]
    groups = sorted((k for k in point if k.rstrip("0123456789") == stem), key=lambda k: int(k[len(stem):] or 1))
    return [str(v).strip() for k in groups for v in point[k]["value"]]


@pytest.mark.parametrize(("markers", "leftover"), [(20, 3), (200, 55), (240, 30), (300, 250)])
def test_unlabeled_points_added_keep_descriptions_and_labels_readable(tmp_path: Path, markers: int,
                                                                      leftover: int) -> None:
    source = _input(tmp_path / "in.c3d", markers)
    take = read_labeled(source)
    unlabeled = np.random.default_rng(1).uniform(-500, 500, (FRAMES, leftover, 3))
    labels = LabeledTrajectories(take.names, take.positions, np.zeros((FRAMES, markers), bool), take.rate,
                                 unlabeled=unlabeled)
    write_labeled(tmp_path / "out.c3d", labels, take.source)
    given, written = ezc3d.c3d(str(source)), ezc3d.c3d(str(tmp_path / "out.c3d"))
    names = _entries(written, "LABELS")
    assert len(names) == markers + leftover == written["data"]["points"].shape[1]
    assert names[:markers] == take.names and all(n.startswith("*") for n in names[markers:])
    if markers + leftover <= 255:  # past that ezc3d's writer drops POINT:DESCRIPTIONS (its own limit)
        assert _entries(written, "DESCRIPTIONS")[:markers] == _entries(given, "DESCRIPTIONS")[:markers]
    assert read_labeled(tmp_path / "out.c3d").names[:markers] == take.names


def test_each_label_keeps_the_residual_and_camera_mask_of_the_sample_it_took(tmp_path: Path) -> None:
    """They were 0 and cleared on every label (every labeled sample "gap-filled", seen by no
    camera); they go with the sample, also when the labels put it under another name."""
    source = _input(tmp_path / "in.c3d", 4)
    c3d = ezc3d.c3d(str(source))
    rng = np.random.default_rng(2)
    c3d["data"]["meta_points"]["residuals"] = rng.uniform(0.1, 2.0, (1, 4, FRAMES)).round(2)
    c3d["data"]["meta_points"]["camera_masks"] = rng.random((7, 4, FRAMES)) < 0.5
    c3d.write(str(source))
    take = read_labeled(source)
    given = ezc3d.c3d(str(source))["data"]["meta_points"]
    swapped = take.positions[:, [1, 0, 2, 3]]  # M0 and M1 exchanged: each holds the other's sample
    hidden = np.zeros((FRAMES, 4), bool)
    hidden[2, 3] = True
    labels = LabeledTrajectories(take.names, np.where(hidden[..., None], np.nan, swapped), hidden, take.rate)
    write_labeled(tmp_path / "out.c3d", labels, take.source)
    meta = ezc3d.c3d(str(tmp_path / "out.c3d"))["data"]["meta_points"]
    order = [1, 0, 2, 3]
    shown = ~hidden.T
    np.testing.assert_allclose(meta["residuals"][0, :4][shown], given["residuals"][0, order][shown], atol=0.01)
    assert (meta["camera_masks"][:, :4][:, shown] == given["camera_masks"][:, order][:, shown]).all()
    assert meta["residuals"][0, 3, 2] < 0 and not meta["camera_masks"][:, 3, 2].any()  # occluded: no sample


@pytest.mark.parametrize("scale", [-0.01, 0.5])
def test_the_header_scale_is_the_parameters_so_strict_readers_open_the_file(tmp_path: Path, scale: float) -> None:
    """ezc3d wrote -1 in the header whatever POINT:SCALE said (-0.01 on Vicon's files); py-c3d
    refuses such a file ("inconsistent scale factor"). A positive (integer-data) scale becomes
    negative: the data are written as floats."""
    source = _input(tmp_path / "in.c3d", 4)
    c3d = ezc3d.c3d(str(source))
    c3d["parameters"]["POINT"]["SCALE"]["value"] = np.array([scale])
    c3d.write(str(source))
    take = read_labeled(source)
    write_labeled(tmp_path / "out.c3d", LabeledTrajectories(take.names, take.positions, np.zeros((FRAMES, 4), bool),
                                                           take.rate), take.source)
    header = (tmp_path / "out.c3d").read_bytes()[:16]
    written = ezc3d.c3d(str(tmp_path / "out.c3d"))
    assert struct.unpack("<f", header[12:16])[0] == pytest.approx(-abs(scale))
    assert written["parameters"]["POINT"]["SCALE"]["value"][0] == pytest.approx(-abs(scale))
    np.testing.assert_allclose(read_labeled(tmp_path / "out.c3d").positions, take.positions, atol=1e-4)


def test_frame_numbers_past_what_a_c3d_header_holds_are_refused_in_one_line(tmp_path: Path) -> None:
    """A TRC trimmed from a long take, numbered from 70001: the C3D's header wrapped it to 4465
    and markerflow then read its own file as truncated."""
    labels = LabeledTrajectories(["A", "B"], np.zeros((5, 2, 3)) + 100.0, np.zeros((5, 2), bool), 100.0)
    write_labeled(tmp_path / "late.trc", labels, SourceFile(first_frame=70000))
    take = read_labeled(tmp_path / "late.trc")
    with pytest.raises(InputError, match=r"out.c3d: a C3D numbers frames up to 65535 and these run from 70000"):
        write_labeled(tmp_path / "out.c3d", labels, take.source)
    assert not (tmp_path / "out.c3d").exists()


def test_relabeling_markerflows_own_output_does_not_grow_it(tmp_path: Path) -> None:
    """Each run emptied the file's *N points over the labeled frames and appended as many new
    ones: 74 -> 75 -> 76 points on walking2. The emptied ones are filled first."""
    source = _input(tmp_path / "in.c3d", 6)
    unlabeled = np.random.default_rng(3).uniform(-500, 500, (FRAMES, 2, 3))
    for run in range(3):
        take = read_labeled(source)
        named = [i for i, name in enumerate(take.names) if not name.startswith("*")]
        labels = LabeledTrajectories([take.names[i] for i in named], take.positions[:, named],
                                     np.zeros((FRAMES, len(named)), bool), take.rate, unlabeled=unlabeled)
        out = tmp_path / f"run{run}.c3d"
        write_labeled(out, labels, take.source)
        assert ezc3d.c3d(str(out))["data"]["points"].shape[1] == 6 + 2, run
        np.testing.assert_allclose(np.sort(read_labeled(out).positions[:, 6:], axis=1), np.sort(unlabeled, axis=1),
                                   atol=1e-3)
        source = out
