"""A .c3d output on a full disk is one line, like any other write failure: with no byte free
ezc3d left an empty file and the header fix-up read past it (``IndexError: index out of
range`` in ``match_header_scale``, exit 1); with a few kB free it already said "came out short"."""

from __future__ import annotations

import contextlib
import os
import struct
import subprocess
from pathlib import Path

import ezc3d
import pytest
from test_cli import assert_input_error, run_cli

import service.io.formats.c3d as c3d_format
from service.errors import InputError
from service.io.formats import write_labeled
from service.io.formats.c3d_layout import match_header_scale
from tests.test_formats import _occluded_cmu

SHORT = r"cannot write \(the file came out short: is the disk full\?\); any earlier file there is untouched"


def _empty_write(self: ezc3d.c3d, path: str) -> None:
    Path(path).write_bytes(b"")  # what a disk with no byte free leaves


def test_an_empty_file_from_ezc3d_is_a_full_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "out.c3d"
    out.write_bytes(b"an earlier file")
    monkeypatch.setattr(ezc3d.c3d, "write", _empty_write)
    with pytest.raises(InputError, match=rf"^{out}: {SHORT}$"):
        write_labeled(out, _occluded_cmu(frames=5))
    assert out.read_bytes() == b"an earlier file" and sorted(p.name for p in tmp_path.iterdir()) == ["out.c3d"]


def test_a_file_cut_short_by_the_channels_rewrite_is_a_full_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Past 255 analog channels the file is written a second time (``fix_channels``)."""
    monkeypatch.setattr(c3d_format, "fix_channels", lambda path, channels: os.truncate(path, 100))
    with pytest.raises(InputError, match=SHORT):
        write_labeled(tmp_path / "out.c3d", _occluded_cmu(frames=5))
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("size", [0, 100, 511])
def test_the_header_scale_leaves_a_short_file_to_the_layout_check(tmp_path: Path, size: int) -> None:
    short = tmp_path / "short.c3d"
    short.write_bytes(b"\x02P" + b"\x00" * max(size - 2, 0) if size else b"")
    match_header_scale(str(short), -0.1)
    assert short.stat().st_size == size


@pytest.mark.parametrize(("processor", "order"), [(84, "<f"), (86, ">f")])
def test_the_header_scale_is_written_in_the_file_s_own_byte_order(tmp_path: Path, processor: int, order: str) -> None:
    """The short-file guard once compared the processor byte as bytes with 86 (MIPS), so a
    big-endian file got its scale little-endian."""
    header = bytearray(1024)
    header[0], header[512 + 3] = 2, processor  # parameters from block 2; its 4th byte the processor type
    path = tmp_path / "scaled.c3d"
    path.write_bytes(bytes(header))
    match_header_scale(str(path), -0.1)
    assert struct.unpack(order, path.read_bytes()[12:16])[0] == pytest.approx(-0.1)


@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root")
def test_track_onto_a_full_tmpfs_is_one_line(tmp_path: Path) -> None:
    disk = tmp_path / "full"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=24k", "tmpfs", str(disk)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        with open(disk / "fill", "wb", buffering=0) as fill, contextlib.suppress(OSError):
            fill.write(b"\0" * 64 * 1024)  # every block taken
        take = tmp_path / "take.csv"
        write_labeled(take, _occluded_cmu(frames=12))
        result = run_cli("-q", "track", take, "--out", disk / "out.c3d", "--start", "1")
        assert_input_error(result, "out.c3d", "came out short")
    finally:
        subprocess.run(["umount", str(disk)], check=False)
