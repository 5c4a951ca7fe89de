"""A write that fails or is interrupted leaves the file the user had, and says so.

TRC and CSV were written straight over the output path: a full disk left a cut file in
place of a good one, and a Ctrl-C during the write a shorter CSV that reads back as a valid
take. A full disk under ezc3d left a short C3D and the run "succeeded". A Ctrl-C or SIGTERM
ended the command with no word at all."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from test_cli import REPO

from service.errors import InputError
from service.io.formats import c3d as c3d_format
from service.io.formats import csv as csv_format
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories

CMU_135 = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "135_02.c3d"


def _labels(frames: int = 50) -> LabeledTrajectories:
    positions = np.random.default_rng(0).uniform(-900, 900, (frames, 5, 3))
    return LabeledTrajectories([f"M{i}" for i in range(5)], positions, np.zeros((frames, 5), bool), 100.0)


@pytest.mark.parametrize("suffix", [".csv", ".trc", ".c3d"])
def test_an_interrupted_write_leaves_the_earlier_file_and_no_debris(tmp_path: Path, suffix: str, monkeypatch) -> None:
    out = tmp_path / f"out{suffix}"
    out.write_text("the earlier, good file")

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    target = {".csv": (csv_format.csv, "writer"), ".trc": (Path, "write_text"), ".c3d": (c3d_format, "fix_channels")}
    monkeypatch.setattr(*target[suffix], interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_labeled(out, _labels())
    assert out.read_text() == "the earlier, good file" and os.listdir(tmp_path) == [out.name]


def test_a_short_c3d_from_a_full_disk_is_an_error_not_a_result(tmp_path: Path, monkeypatch) -> None:
    out = tmp_path / "out.c3d"
    written = c3d_format.fix_channels

    def disk_full(name: str, channels: object) -> None:  # what ezc3d leaves on ENOSPC: the file cut short
        written(name, channels)
        with open(name, "r+b") as f:
            f.truncate(os.path.getsize(name) // 2)

    monkeypatch.setattr(c3d_format, "fix_channels", disk_full)
    with pytest.raises(InputError, match=r"out.c3d: cannot write \(the file came out short: is the disk full\?\)"):
        write_labeled(out, _labels(2000))
    assert not out.exists() and os.listdir(tmp_path) == []


@pytest.mark.skipif(not CMU_135.exists(), reason="needs ../shared/data")
@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_ctrl_c_or_sigterm_mid_take_says_so_and_keeps_the_earlier_output(tmp_path: Path, signum: int,
                                                                        code: int) -> None:
    out = tmp_path / "out.csv"
    out.write_text("the earlier, good file")
    command = [sys.executable, "-m", "service.cli", "track", str(CMU_135), "--out", str(out)]
    # a shell's background job inherits SIGINT ignored (as `make test &` does): the command
    # gets the default a terminal gives it
    with subprocess.Popen(command, cwd=REPO, stderr=subprocess.PIPE, text=True,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL)) as run:
        assert run.stderr is not None
        first = run.stderr.readline()  # the first progress line: labeling is under way
        assert first.startswith("labeling 135_02.c3d: "), first
        run.send_signal(signum)
        rest = run.stderr.read()
    assert run.returncode == code
    assert rest.strip().splitlines()[-1].startswith("interrupted: stopped before the end, no output written")
    assert out.read_text() == "the earlier, good file"


def _cut_picture(self: object, fname: object, *args: object, **kwargs: object) -> None:
    """savefig stopped by a Ctrl-C after part of the PNG: what a signal mid-write leaves."""
    Path(str(fname)).write_bytes(b"\x89PNG\r\n\x1a\n cut short")
    raise KeyboardInterrupt


def _write_trajectory_plot(path: Path) -> None:
    from service.evaluation.plot import plot_trajectories

    plot_trajectories(_labels(20), path)


def _write_pose_overlay(path: Path) -> None:
    from pose_scenes import walking
    from test_pose_cli import CALIBRATION

    from formulations.pose.human import human_model
    from formulations.pose.kinematics import forward_kinematics
    from service.io.calibration import load_calibration
    from service.pose.overlay import write_overlay

    if not CALIBRATION.exists():
        pytest.skip("Pose2Sim demo calibration not present")
    model = human_model()
    positions = forward_kinematics(model, walking(model, 4)).positions
    write_overlay(path, load_calibration(CALIBRATION)[0], model, positions, "take")


def _write_demo_capture(path: Path) -> None:
    from service.cli.demo import _write_capture
    from service.evaluation.scenario import Scenario
    from service.evaluation.scene import generate_scene
    from service.evaluation.simulate_cloud import simulate_cloud

    _write_capture(path, simulate_cloud(generate_scene(n_frames=5), Scenario()))


@pytest.mark.parametrize(("writer", "name"), [(_write_trajectory_plot, "demo_trajectories.png"),
                                              (_write_pose_overlay, "pose.png"),
                                              (_write_demo_capture, "demo_capture.json")])
def test_an_interrupted_picture_or_capture_leaves_the_earlier_file_and_no_debris(tmp_path: Path, monkeypatch,
                                                                                writer, name: str) -> None:
    """The demo's PNG and capture JSON and pose's PNG were written straight to their paths: a
    Ctrl-C mid-write left a cut file where the earlier one was."""
    from matplotlib.figure import Figure

    out = tmp_path / name
    out.write_text("the earlier, good file")
    write_text = Path.write_text

    def cut_text(self: Path, data: str, *args: object, **kwargs: object) -> int:
        write_text(self, data[:20], *args, **kwargs)  # type: ignore[arg-type]
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", _cut_picture)
    monkeypatch.setattr(Path, "write_text", cut_text)
    with pytest.raises(KeyboardInterrupt):
        writer(out)
    assert out.read_bytes() == b"the earlier, good file" and os.listdir(tmp_path) == [name]


def test_a_demo_interrupted_after_its_first_output_names_it_and_leaves_the_others(tmp_path: Path, monkeypatch,
                                                                                 capsys) -> None:
    """Ctrl-C while the demo drew its PNG, after its C3D was written: the message said "no output
    written" of a folder holding the new C3D beside a cut PNG."""
    from matplotlib.figure import Figure

    from service.cli.entry import main

    names = ("demo_labeled.c3d", "demo_trajectories.png", "demo_capture.json")
    for name in names:
        (tmp_path / name).write_text("the earlier, good file")
    monkeypatch.setattr(Figure, "savefig", _cut_picture)
    assert main(["-q", "demo", "--out", str(tmp_path), "--frames", "5"]) == 130
    said = capsys.readouterr().err.strip().splitlines()[-1]
    assert said == (f"interrupted: stopped before the end, after writing {tmp_path / names[0]} whole; no other output "
                    "written (an earlier file at their paths is untouched)")
    assert read_labeled(tmp_path / names[0]).n_frames == 5  # the new C3D, whole
    assert [(tmp_path / name).read_text() for name in names[1:]] == ["the earlier, good file"] * 2
    assert sorted(os.listdir(tmp_path)) == sorted(names)



def test_an_interrupted_mot_result_or_choices_file_leaves_the_earlier_one(tmp_path: Path, monkeypatch) -> None:
    """``boxes`` and ``best-view`` wrote straight over their output: a Ctrl-C mid-write left a
    cut file while the message said the earlier one was untouched."""
    from service.best_view.tables import ObjectCosts, write_choices
    from service.boxes.detections import BoxTracks
    from service.boxes.mot_files import write_tracks

    tracks = BoxTracks(frame=np.array([1, 2]), track_id=np.array([1, 1]), box=np.ones((2, 4)),
                       confidence=np.ones(2), n_frames=2, occluded=np.zeros(2, bool))
    objects = [ObjectCosts("a", np.array([1, 2]), np.zeros((2, 2)))]
    writes = {"result.txt": lambda out: write_tracks(out, tracks),
              "choices.csv": lambda out: write_choices(out, ["c1", "c2"], objects, [np.array([0, 1])])}
    real_write = Path.write_text

    def cut(self: Path, text: str, *args: object, **kwargs: object) -> None:
        real_write(self, text[: len(text) // 2])
        raise KeyboardInterrupt

    for name, write in writes.items():
        out = tmp_path / name
        out.write_text("the earlier, good file")
        with monkeypatch.context() as patched:
            patched.setattr(Path, "write_text", cut)
            patched.setattr("csv.writer", lambda f: (_ for _ in ()).throw(KeyboardInterrupt()))
            with pytest.raises(KeyboardInterrupt):
                write(out)
        assert out.read_text() == "the earlier, good file", name
    assert sorted(os.listdir(tmp_path)) == ["choices.csv", "result.txt"]


def test_ctrl_c_while_the_command_line_is_imported_is_one_line(monkeypatch, capsys) -> None:
    """The first second of a run imports numpy, scipy and the rest: a Ctrl-C there printed a traceback."""
    import types

    from service.cli import launch

    class Importing(types.ModuleType):
        def __getattr__(self, name: str) -> object:
            raise KeyboardInterrupt

    monkeypatch.setitem(sys.modules, "service.cli.entry", Importing("service.cli.entry"))
    with pytest.raises(SystemExit) as stopped:
        launch.run()
    assert stopped.value.code == 130
    assert capsys.readouterr().err == "interrupted: stopped before the end, no output written\n"


def test_a_reader_meeting_a_files_end_early_is_an_error_line_not_aborted(monkeypatch, capsys) -> None:
    """Typer turns any EOFError into Abort, printed as a bare "aborted" (exit 1); no command prompts."""
    from service.cli import entry

    def cut_short(*args: object, **kwargs: object) -> None:
        raise entry.typer.Abort  # what click raises from a command's EOFError (numpy.load of an empty .npz)

    monkeypatch.setattr(entry, "app", cut_short)
    assert entry.main(["demo"]) == 2
    assert "error: a file ended before its reader expected (cut short?)" in capsys.readouterr().err
