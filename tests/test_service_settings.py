"""Service settings: the documented config is the defaults; options beat environment beat file."""

from __future__ import annotations

import re

import pytest
from service_fixtures import REPO

from service.errors import InputError
from service.server.settings import Limits, Settings, load_settings

CONFIG = REPO / "configs" / "service.toml"


def test_service_toml_documents_every_setting_at_its_default(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    text = CONFIG.read_text()
    for name in [*Settings.model_fields, *Limits.model_fields]:
        assert re.search(rf"^(#? ?{name} =|\[{name}\])", text, re.MULTILINE), f"{name} is not in {CONFIG.name}"
    assert load_settings(CONFIG).model_dump() == Settings().model_dump()


def test_options_override_environment_override_file(monkeypatch, tmp_path):
    config = tmp_path / "service.toml"
    config.write_text('port = 9000\nmax_parallel_jobs = 3\n[limits]\nmax_frames = 10\n')
    monkeypatch.setenv("MARKERFLOW_PORT", "9100")
    monkeypatch.setenv("MARKERFLOW_LIMITS__MAX_MARKERS", "7")
    settings = load_settings(config, port=None, host="::1")
    assert (settings.port, settings.host, settings.max_parallel_jobs) == (9100, "::1", 3)
    assert (settings.limits.max_frames, settings.limits.max_markers) == (10, 7)
    assert load_settings(config, port=9200).port == 9200


def test_bad_settings_are_one_line_naming_the_key(tmp_path):
    config = tmp_path / "service.toml"
    config.write_text("[limits]\nmax_frames = -1\n")
    with pytest.raises(InputError, match=r"service.toml: limits.max_frames: Input should be greater than 0"):
        load_settings(config)
    config.write_text("[tokens]\nalice = 'short'\n")
    with pytest.raises(InputError, match="tokens: .*at least 16 characters"):
        load_settings(config)
    with pytest.raises(InputError, match="no such config file"):
        load_settings(tmp_path / "missing.toml")
    with pytest.raises(InputError, match="is not a database URL"):
        load_settings(db="markerflow.db")
