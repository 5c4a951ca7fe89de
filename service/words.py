"""Counted nouns for the lines markerflow prints, shared by the CLI and the labeling's warnings."""


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """``1 marker``, ``2 markers`` (``plural`` for nouns that do not take an s)."""
    return f"{count} {noun if count == 1 else plural or noun + 's'}"
