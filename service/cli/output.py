"""Fail before the work, not after it, when the output cannot be written."""

from __future__ import annotations

import tempfile
from pathlib import Path

from service.errors import InputError
from service.io.formats import check_output


def check_writable_output(path: Path) -> None:
    """A supported suffix in an existing folder (``check_output``) that takes a file.

    Raises:
        InputError: unsupported suffix, a missing folder, or one this user cannot write in.
    """
    check_output(path)
    check_writable_folder(path.parent)


def check_writable_folder(folder: Path) -> None:
    """Create and remove a file in ``folder``: permission bits, read-only mounts and ACLs
    all answer the same way, where ``os.access`` would miss some.

    Raises:
        InputError: the folder cannot take a new file.
    """
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".markerflow-probe-"):
            pass
    except OSError as error:
        raise InputError(f"{folder}: cannot write there ({error.strerror})") from None
