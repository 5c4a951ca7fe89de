"""The marker names every result format carries back unchanged, checked where names come in."""

from __future__ import annotations

import unicodedata

from service.io.recording import UNLABELED_PREFIX, is_unlabeled

MAX_NAME_BYTES = 255  # a C3D parameter's dimensions are single bytes: longer labels make an unreadable file


def name_problem(name: str) -> str | None:
    """What keeps ``name`` from coming back from every output as itself, or None.

    C3D strips labels and cuts them at a NUL (``L.ASIS\\x00x`` came back ``L.ASISx``), a TRC
    or CSV line break splits its row, and a label over ``MAX_NAME_BYTES`` makes a C3D no
    reader opens: a blank, padded, overlong or control-character name would come back as
    another name, or not at all.
    """
    if not name.strip():
        return "is blank"
    if name != name.strip():
        return "starts or ends with whitespace"
    if any(unicodedata.category(char) == "Cc" for char in name):
        return "has a control character"
    if len(name.encode()) > MAX_NAME_BYTES:
        return f"is longer than {MAX_NAME_BYTES} bytes (UTF-8)"
    return None


def first_name_problem(names: list[str]) -> tuple[str, str] | None:
    """``(name, problem)`` of the first of ``names`` with a ``name_problem``, or None."""
    for name in names:
        problem = name_problem(name)
        if problem:
            return name, problem
    return None


def shown(name: str) -> str:
    """``name`` quoted for a one-line message: control characters escaped, cut at 40 characters."""
    return repr(name[:40]) + ("..." if len(name) > 40 else "")


def check_marker_names(names: list[str], path: str) -> None:
    """Every name survives every result format unchanged (``name_problem``), and none is a
    C3D's name of an unlabeled trajectory ``*N``: readers, markerflow's too, take such a
    point for one, so the marker would vanish from the output read back.

    Raises:
        ValueError: ``<path with {i} filled in>: marker name ...`` for the first name that would not.
    """
    for i, name in enumerate(names):
        problem = name_problem(name)
        if problem is None and is_unlabeled(name):
            problem = f"is how a C3D names an unlabeled trajectory ({UNLABELED_PREFIX}N), not a marker; rename it"
        if problem:
            raise ValueError(f"{path.format(i=i)}: marker name {shown(name)} {problem}")
