"""Reading a TOML file with one-line errors (presets, scenarios, marker sets)."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from service.errors import InputError
from service.io.utf8 import utf8_file


def read_toml(path: str | Path) -> dict[str, Any]:
    """The file's tables.

    TOML is UTF-8 by definition; a byte-order mark, which Windows editors put first, is
    skipped (tomllib alone took it for a statement at line 1, column 1).

    Raises:
        InputError: ``<path>: cannot read (...)``, ``<path>: not UTF-8 text (...)`` or
            ``<path>: not valid TOML (...)``.
    """
    text = utf8_file(path)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: not valid TOML ({error})") from None
