"""Uploaded files are read in a bounded child process: a crash, a memory bomb or a slow read
is a 422 naming the file, and the server (a real subprocess) stays up with bounded memory."""

from __future__ import annotations

import numpy as np
import pytest
from service_fixtures import FUZZ_C3D, RELIABILITY, ServerProcess, fuzz_uploads, serving, upload_fuzz

from service.errors import InputError
from service.io.formats import read_labeled
from service.io.isolated import ReaderBounds, _answer, read_isolated
from service.server.settings import Limits, Settings

BOUNDS = ReaderBounds(memory_bytes=2**30, seconds=30)
FUZZ_COUNT, FUZZ_SEED = 60, 15
PEAK_RSS_MIB = 600  # the server's own peak while it takes the fuzz uploads (reader children excluded)


def test_a_good_file_reads_as_in_process():
    recording, direct = read_isolated(FUZZ_C3D.read_bytes(), ".c3d", BOUNDS), read_labeled(FUZZ_C3D)
    assert recording.positions.shape == (810, 41, 3) and recording.rate == direct.rate == 120.0
    assert recording.names == direct.names
    np.testing.assert_array_equal(recording.positions, direct.positions)  # NaN gaps in the same places


@pytest.mark.parametrize(("name", "message"), [
    ("segv.c3d", "C3D parameter record at byte 962 has 146 dimensions (at most 7)"),
    ("bomb.c3d", "C3D parameter record at byte 962 overruns the next record"),
    ("badlabel.c3d", r"C3D point 16 of 39 has a label that is not UTF-8 text (LF\udcfeM)"),
])
def test_the_issue_reproducers_are_refused_before_the_c3d_reader_runs(name, message):
    with pytest.raises(InputError) as refused:
        read_isolated((RELIABILITY / name).read_bytes(), ".c3d", BOUNDS)
    assert str(refused.value) == message


def test_time_memory_and_header_limits_are_named():
    data = FUZZ_C3D.read_bytes()
    with pytest.raises(InputError, match=r"took longer than the limit of 0.001 s \(limits.reader_seconds\)"):
        read_isolated(data, ".c3d", ReaderBounds(2**30, 0.001))
    with pytest.raises(InputError, match=r"limit of 1 MiB of memory \(limits.reader_memory_bytes\)|bad_alloc"):
        read_isolated(data, ".c3d", ReaderBounds(2**20, 30))
    with pytest.raises(InputError, match=r"^41 points exceeds the limit of 10 \(limits.max_markers\)$"):
        read_isolated(data, ".c3d", ReaderBounds(2**30, 30, max_markers=10))
    with pytest.raises(InputError, match=r"^810 frames exceeds the limit of 600 \(limits.max_frames\)$"):
        read_isolated(data, ".c3d", ReaderBounds(2**30, 30, max_frames=600))


def test_a_crashed_or_silent_reader_is_an_input_error():
    with pytest.raises(InputError, match=r"^the reader crashed \(SIGSEGV\) on this file$"):
        _answer(b"", -11, BOUNDS)
    with pytest.raises(InputError, match=r"exit status 1"):
        _answer(b"", 1, BOUNDS)


def test_uploads_over_the_header_limits_are_422_naming_file_and_limit(tmp_path):
    limits = Limits(max_markers=10)
    with serving(Settings(db=f"sqlite:///{tmp_path / 'jobs.db'}", limits=limits)) as client:
        answer = client.post("/v1/jobs", files={"file": ("take.c3d", FUZZ_C3D.read_bytes())})
        assert answer.status_code == 422
        assert answer.json() == {"message": "file: take.c3d: 41 points exceeds the limit of 10 (limits.max_markers)"}


def test_the_server_survives_mutated_uploads_with_bounded_memory(tmp_path):
    server = ServerProcess(f"sqlite:///{tmp_path / 'jobs.db'}", tmp_path / "server.log",
                           env={"MARKERFLOW_MAX_PARALLEL_JOBS": "1"})
    try:
        answers = upload_fuzz(server.url, fuzz_uploads(FUZZ_COUNT, FUZZ_SEED))
        assert server.process.poll() is None, server.log.read_text()[-2000:]
        assert {label: answer for label, answer in answers.items() if answer[0] != 202 and not 400 <= answer[0] < 500} == {}
        assert all(answers[name][0] == 422 for name in ("segv.c3d", "bomb.c3d", "badlabel.c3d"))
        assert server.peak_rss_mib() < PEAK_RSS_MIB
    finally:
        server.stop()


def test_trc_header_counts_are_checked_before_any_row():
    header = "PathFileType\t4\t(X/Y/Z)\ttake.trc\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n"
    trc = f"{header}100\t100\t2\t5000\tmm\nFrame#\tTime\tA\n\t\tX1\tY1\tZ1\n".encode()
    with pytest.raises(InputError, match=r"^5000 markers exceeds the limit of 300 \(limits.max_markers\)$"):
        read_isolated(trc, ".trc", ReaderBounds(2**30, 30, max_markers=300))
