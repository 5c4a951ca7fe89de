"""TOML presets, scenarios and marker sets saved by Windows editors: a Windows-1252 or UTF-16
file was a ``UnicodeDecodeError`` traceback (exit 1), and a UTF-8 byte-order mark was "not
valid TOML (Invalid statement (at line 1, column 1))"."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_cli import CMU, assert_input_error, run_cli

from service.errors import InputError
from service.io.toml_file import read_toml

PRESET = '# réglages\n[formulation]\nname = "lp-l1"\n'


@pytest.mark.parametrize("encoding", ["cp1252", "utf-16"])
def test_a_toml_not_in_utf8_is_refused_naming_the_file(tmp_path: Path, encoding: str) -> None:
    path = tmp_path / "preset.toml"
    path.write_bytes(PRESET.encode(encoding))
    with pytest.raises(InputError, match=r"preset.toml: not UTF-8 text .*save it as UTF-8"):
        read_toml(path)


def test_a_toml_with_a_byte_order_mark_is_read(tmp_path: Path) -> None:
    path = tmp_path / "preset.toml"
    path.write_bytes(PRESET.encode("utf-8-sig"))
    assert read_toml(path) == {"formulation": {"name": "lp-l1"}}


def test_track_refuses_a_cp1252_preset_in_one_line(tmp_path: Path) -> None:
    preset = tmp_path / "f.toml"
    preset.write_bytes(PRESET.encode("cp1252"))
    result = run_cli("track", CMU, "--out", tmp_path / "out.c3d", "--formulation", preset)
    assert_input_error(result, "f.toml", "UTF-8")
