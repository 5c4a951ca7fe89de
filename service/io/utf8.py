"""Text of a format that is UTF-8 by definition (JSON, TOML) or plain ASCII numbers (MOTChallenge
files), as Windows editors save it: a byte-order mark first."""

from __future__ import annotations

from pathlib import Path

from service.errors import InputError


def utf8_text(data: bytes) -> str:
    """``data`` decoded as UTF-8, a leading byte-order mark skipped (json and tomllib took it
    for a statement at line 1, column 1).

    Raises:
        InputError: ``not UTF-8 text (byte N is 0x..); save it as UTF-8`` (callers prefix the source).
    """
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise InputError(f"not UTF-8 text (byte {error.start + 1} is 0x{data[error.start]:02x}); "
                         "save it as UTF-8") from None


def utf8_file(path: str | Path) -> str:
    """``utf8_text`` of the file at ``path``, its errors prefixed with the path.

    Raises:
        InputError: ``<path>: cannot read (...)`` or ``<path>: not UTF-8 text (...)``.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror})") from None
    try:
        return utf8_text(data)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
