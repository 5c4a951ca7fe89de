"""Output written beside its path and renamed onto it only once it is whole.

A full disk, a Ctrl-C or a SIGTERM in the middle of a write must not leave half a take
where the user had a whole one: a CSV cut after a complete row even reads back as a valid,
shorter take. ``os.replace`` is atomic on one file system, so readers see the old file or
the new one, never a mix. A command that writes several outputs can be stopped between two
of them: ``watching_replaced`` tells which it did replace, for its interrupt message.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from service.errors import InputError

Identity = tuple[int, int] | None  # a file's (device, inode); None: no file
_watchers: list[dict[Path, Identity]] = []  # one per open watching_replaced


@contextmanager
def replacing(path: Path, suffix: str | None = None) -> Iterator[Path]:
    """A new hidden file beside ``path`` (ending ``suffix``, else ``path``'s) to write; renamed
    onto ``path`` when the block ends, removed if it raises or is interrupted.

    Raises:
        InputError: the file system refused (a full disk, no permission), naming ``path``.
    """
    for watched in _watchers:
        watched.setdefault(path, _identity(path))
    temp = path.with_name(f".{path.stem}-{secrets.token_hex(6)}{path.suffix if suffix is None else suffix}")
    try:
        yield temp
        os.replace(temp, path)
    except OSError as error:
        raise InputError(f"{path}: cannot write ({error.strerror}); any earlier file there is untouched") from None
    finally:
        if temp.exists():
            temp.unlink()


@contextmanager
def watching_replaced() -> Iterator[Callable[[], list[Path]]]:
    """While the block runs, the file at each path ``replacing`` is asked to write is noted; the
    function yielded lists the paths that hold another file since, in order: the outputs a
    command stopped part way did write whole. Asked of the file system, not noted after the
    rename, so an interrupt that lands just after it is not missed."""
    watched: dict[Path, Identity] = {}
    _watchers.append(watched)
    try:
        yield lambda: [path for path, before in watched.items() if _identity(path) != before]
    finally:
        _watchers.remove(watched)


def _identity(path: Path) -> Identity:
    """The file at ``path`` (device, inode), None if none: a rename onto it gives it the new file's."""
    try:
        found = os.stat(path)
    except OSError:
        return None
    return found.st_dev, found.st_ino
