"""Reading a TOML file with one-line errors (presets, scenarios, marker sets)."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from service.errors import InputError


def read_toml(path: str | Path) -> dict[str, Any]:
    """The file's tables.

    Raises:
        InputError: ``<path>: cannot read (...)`` or ``<path>: not valid TOML (...)``.
    """
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: not valid TOML ({error})") from None
