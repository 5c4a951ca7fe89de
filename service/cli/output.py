"""Fail before the work, not after it, when the output cannot be written."""

from __future__ import annotations

import tempfile
from pathlib import Path

from service.errors import InputError
from service.io.formats import check_output


def check_writable_output(path: Path, *inputs: Path, labeled: bool = True) -> None:
    """A supported suffix in an existing folder (``check_output``) that takes a file, and
    none of ``inputs``: writing over the take being read would lose it for good.

    ``labeled=False`` for an output that is not labeled trajectories (``model``'s JSON,
    ``boxes``' result, ``best-view``'s CHOICES.csv): the same checks but the suffix, so a
    folder as the output is refused before the work, not after it.

    Raises:
        InputError: unsupported suffix, a folder as the path, a missing folder, one this user
            cannot write in, or an input's own path.
    """
    check_output(path, labeled)
    check_not_input(path, *inputs)
    check_writable_folder(path.parent)


def check_not_input(path: Path, *inputs: Path) -> None:
    """Refuse an output that is one of ``inputs``: the labels would replace the take for good.

    Raises:
        InputError: ``path`` names the same file as an input (links and relative paths resolved).
    """
    for given in inputs:
        if path.resolve() == given.resolve():
            raise InputError(f"{path}: is the input {given}; write the output to another file")


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
