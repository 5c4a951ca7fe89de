"""Every sample of a C3D output keeps the residual and camera mask of the input sample it is,
the unlabeled ``*N`` ones too (points no marker took, and the input's samples outside
``--start/--end``). Those got residual 0, which Nexus and Visual3D read as gap-filled, and no
camera. Round trip through the real ezc3d on a real take with camera masks."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
from test_cli import DATA, run_cli

ROLLING = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "03_rolling.c3d"


def _with_residuals(path: Path) -> Path:
    """The take with a distinct residual on each present sample (its own are all 0 there)."""
    c3d = ezc3d.c3d(str(ROLLING))
    present = (c3d["data"]["points"][:3] != 0).any(axis=0)
    residuals = np.random.default_rng(7).uniform(0.1, 3.0, present.shape).round(2)
    c3d["data"]["meta_points"]["residuals"][0] = np.where(present, residuals, -1.0)
    c3d.write(str(path))
    return path


def test_every_output_sample_keeps_its_input_samples_residual_and_camera_mask(tmp_path: Path) -> None:
    source = _with_residuals(tmp_path / "in.c3d")
    result = run_cli("-q", "track", source, "--start", "562", "--end", "700", "--out", tmp_path / "out.c3d")
    assert result.returncode == 0, result.stderr
    given, written = ezc3d.c3d(str(source)), ezc3d.c3d(str(tmp_path / "out.c3d"))
    points, meta = given["data"]["points"][:3], given["data"]["meta_points"]
    out, out_meta = written["data"]["points"][:3], written["data"]["meta_points"]
    labels = [str(label) for label in written["parameters"]["POINT"]["LABELS"]["value"]]
    unlabeled = np.array([label.startswith("*") for label in labels])
    checked = {True: 0, False: 0}
    seen = {True: 0, False: 0}  # samples with a camera, so a cleared mask would show
    for column in range(out.shape[1]):
        for frame in np.flatnonzero(out_meta["residuals"][0, column] >= 0):
            gap = np.linalg.norm(points[:, :, frame] - out[:, column, frame][:, None], axis=0)
            gap[meta["residuals"][0, :, frame] < 0] = np.inf
            sample = int(np.argmin(gap))
            if gap[sample] > 1e-3:
                continue  # not an input sample (a filled gap)
            checked[unlabeled[column]] += 1
            seen[unlabeled[column]] += int(meta["camera_masks"][:, sample, frame].any())
            assert abs(out_meta["residuals"][0, column, frame] - meta["residuals"][0, sample, frame]) < 0.01, \
                (labels[column], frame)
            assert (out_meta["camera_masks"][:, column, frame] == meta["camera_masks"][:, sample, frame]).all(), \
                (labels[column], frame)
    # the *N hold points no marker took inside the span and the input's samples outside it
    assert checked[True] > 100_000 and checked[False] > 7_000, checked
    assert seen[True] > 10_000 and seen[False] > 1_000, seen
    inside = out_meta["residuals"][0, unlabeled, 562:700] >= 0
    assert inside.sum() > 300  # leftover points of the labeled frames, not only the input's outside them
