"""The service's settings: command-line options over ``MARKERFLOW_*`` environment over a TOML file.

``configs/service.toml`` documents every key. Nested keys come from the environment with a
double underscore: ``MARKERFLOW_LIMITS__MAX_FRAMES=5000``; tokens as JSON:
``MARKERFLOW_TOKENS='{"alice": "..."}'``.
"""

from __future__ import annotations

import hashlib
import ipaddress
import tomllib
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict, TomlConfigSettingsSource
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError

from service.capture.document import describe_validation_error
from service.errors import InputError

LOCAL_OWNER = "local"


class Limits(BaseModel):
    """What one request may ask for; beyond it the answer is 413 (body) or 422 (content)."""

    model_config = ConfigDict(extra="forbid")
    # Defaults by keyword: type checkers take only a keyword default for one (Limits() needs no argument).
    max_body_bytes: int = Field(default=64 * 2**20, gt=0)
    max_frames: int = Field(default=100_000, gt=0)
    max_markers: int = Field(default=300, gt=0)
    max_points_per_frame: int = Field(default=2_000, gt=0)
    max_detections_per_camera: int = Field(default=2_000, gt=0)
    max_cameras: int = Field(default=64, gt=0)
    max_solve_frames: int = Field(default=200, ge=2)
    # A job's window: its LP grows with it; Vicon.c3d at 580 frames a window was still in its
    # first window after 4 minutes, holding one of the job slots (the default window is 20).
    max_window: int = Field(default=250, ge=2)
    reader_memory_bytes: int = Field(default=2 * 2**30, gt=0)
    reader_seconds: float = Field(default=60.0, gt=0)


class Settings(BaseSettings):
    """Where to listen, what to store in, where to run, who may ask, and how much."""

    model_config = SettingsConfigDict(env_prefix="MARKERFLOW_", env_nested_delimiter="__", extra="forbid")
    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=0, le=65535)
    db: str = "sqlite:///markerflow.db"
    dask: str | None = None
    max_parallel_jobs: int = Field(default=2, gt=0)
    events_poll_seconds: float = Field(default=0.2, gt=0)
    max_event_streams_per_token: int = Field(default=20, gt=0)
    read_timeout_seconds: float = Field(default=10.0, gt=0)
    shutdown_grace_seconds: float = Field(default=10.0, gt=0)
    max_queued_jobs: int = Field(default=1000, gt=0)
    retry_after_seconds: int = Field(default=10, gt=0)
    api_docs: bool = True
    tokens: dict[str, str] | list[str] = Field(default_factory=dict, repr=False)  # secrets stay out of logs
    limits: Limits = Field(default_factory=Limits)

    @classmethod
    def settings_customise_sources(cls, settings_cls, init_settings, env_settings, dotenv_settings, file_secret_settings):
        return init_settings, env_settings, TomlConfigSettingsSource(settings_cls)

    @field_validator("db")
    @classmethod
    def _absolute_sqlite(cls, db: str) -> str:
        """A SQLite path is made absolute now, so Dask workers elsewhere open the same file."""
        try:
            url = make_url(db)
        except ArgumentError:
            raise ValueError(f"{db!r} is not a database URL (e.g. sqlite:///markerflow.db)") from None
        if url.get_backend_name() == "sqlite":
            if url.database in (None, "", ":memory:"):
                # each process (and pooled thread) would get its own empty database: jobs
                # would be queued where no worker can see them, and stay queued
                raise ValueError(f"{db!r}: an in-memory SQLite database is private to each process, and the service's "
                                 "workers run in their own; give a file path (e.g. sqlite:///markerflow.db)")
            url = url.set(database=str(Path(url.database).resolve()))
        return url.render_as_string(hide_password=False)

    @field_validator("tokens")
    @classmethod
    def _long_secrets(cls, tokens: dict[str, str] | list[str]) -> dict[str, str] | list[str]:
        secrets = tokens.values() if isinstance(tokens, dict) else tokens
        if any(len(secret) < 16 for secret in secrets):
            raise ValueError("every token secret needs at least 16 characters")
        return tokens

    def owners(self) -> dict[str, str]:
        """Secret -> owner name; a bare secret's owner is a digest of it (stable, not revealing)."""
        if isinstance(self.tokens, dict):
            return {secret: name for name, secret in self.tokens.items()}
        return {secret: "token-" + hashlib.sha256(secret.encode()).hexdigest()[:12] for secret in self.tokens}

    def check_exposure(self) -> None:
        """Refuse to serve beyond this machine without tokens.

        Raises:
            InputError: A non-loopback host and no tokens.
        """
        if not self.tokens and not is_loopback(self.host):
            raise InputError(
                f"refusing to serve on {self.host} without tokens: put at least one token in the config's "
                "[tokens] table (owner = \"secret of 16+ characters\", see configs/service.toml) or bind to 127.0.0.1"
            )


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:  # a host name other than localhost may resolve anywhere
        return False


def load_settings(config: Path | None = None, **options: Any) -> Settings:
    """Settings from ``config`` (TOML), the environment, and ``options`` (None: not given).

    Raises:
        InputError: Missing or malformed file, or a setting out of range, named.
    """
    given = {key: value for key, value in options.items() if value is not None}
    source = "settings"
    cls = Settings
    if config is not None:
        if not config.is_file():
            raise InputError(f"{config}: no such config file")
        source = str(config)
        cls = _read_from(config)
    try:
        return cls(**given)
    except ValidationError as error:
        raise InputError(f"{source}: {describe_validation_error(error)}") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{source}: not valid TOML ({error})") from None


def _read_from(config: Path) -> type[Settings]:
    """``Settings`` whose TOML source is ``config``."""

    class FileSettings(Settings):
        model_config = SettingsConfigDict(toml_file=config)

    return FileSettings
