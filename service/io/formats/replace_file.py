"""Output written beside its path and renamed onto it only once it is whole.

A full disk, a Ctrl-C or a SIGTERM in the middle of a write must not leave half a take
where the user had a whole one: a CSV cut after a complete row even reads back as a valid,
shorter take. ``os.replace`` is atomic on one file system, so readers see the old file or
the new one, never a mix.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from service.errors import InputError


@contextmanager
def replacing(path: Path, suffix: str | None = None) -> Iterator[Path]:
    """A new hidden file beside ``path`` (ending ``suffix``, else ``path``'s) to write; renamed
    onto ``path`` when the block ends, removed if it raises or is interrupted.

    Raises:
        InputError: the file system refused (a full disk, no permission), naming ``path``.
    """
    temp = path.with_name(f".{path.stem}-{secrets.token_hex(6)}{path.suffix if suffix is None else suffix}")
    try:
        yield temp
        os.replace(temp, path)
    except OSError as error:
        raise InputError(f"{path}: cannot write ({error.strerror}); any earlier file there is untouched") from None
    finally:
        if temp.exists():
            temp.unlink()
