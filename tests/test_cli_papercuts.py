"""Papercuts of the command line a new user met, each fixed: help texts, ``serve --db``, C3D errors."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_cli import CMU, REPO


def test_help_texts_show_bracketed_words_and_cite_what_exists() -> None:
    def wide_help(command: str) -> str:
        env = {**os.environ, "COLUMNS": "250"}
        return subprocess.run([sys.executable, "-m", "service.cli", command, "--help"], cwd=REPO, env=env,
                              capture_output=True, text=True, timeout=60).stdout

    help_text = wide_help("track")
    assert "TOML file with a [formulation] table" in help_text
    assert 'see "Capture JSON" in README.md' in help_text and "## Capture JSON" in (REPO / "README.md").read_text()
    assert "TOML with a [formulation] table" in wide_help("integrality")


def test_serve_db_takes_a_plain_path() -> None:
    from service.cli.serve import database_url
    from service.server.settings import load_settings

    assert database_url("markerflow.db") == "sqlite:///markerflow.db"
    assert database_url("postgresql://u@h/db") == "postgresql://u@h/db" and database_url(None) is None
    settings = load_settings(None, db=database_url("jobs/markerflow.db"))
    assert settings.db == f"sqlite:///{Path('jobs/markerflow.db').resolve()}"


def test_c3d_errors_do_not_advise_an_ezc3d_option(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from service.errors import InputError
    from service.io.formats import c3d

    def refuse(path: str) -> None:
        raise RuntimeError("The format is not standard. If you want to ignore this error, set ignoreBadFormatting to true")

    monkeypatch.setattr(c3d.ezc3d, "c3d", refuse)
    with pytest.raises(InputError) as error:
        c3d.read_c3d(CMU)
    assert "The format is not standard" in str(error.value) and "ignoreBadFormatting" not in str(error.value)
