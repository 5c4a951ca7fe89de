"""What ``track``'s summary line says of the labelings beyond the first: the second pass, the
frame-by-frame reading and the ``mht`` reading (``service.labeling.second_pass``,
``service.labeling.rival_reading``, ``service.labeling.hypothesis_reading``)."""

from __future__ import annotations

from service.labeling.rival_reading import RivalChoice
from service.labeling.second_pass import PassChoice
from service.words import counted


def second_pass_note(choice: PassChoice | None) -> str:
    """What the summary line says of a second pass that ran: which labeling was kept, and why."""
    if choice is None or choice.second_doubtful is None:
        return ""
    kept = "second pass kept" if choice.kept == 2 else "first pass kept over a second"
    off = "" if choice.first_off_mm is None or choice.second_off_mm is None else (
        f"rigid pairs {choice.first_off_mm:.1f} -> {choice.second_off_mm:.1f} mm off the first frame; ")
    other = "" if not choice.taken_from_other else f", {counted(choice.taken_from_other, 'marker')}' labels from the other pass"
    return f"; {kept} ({off}{choice.first_doubtful:.1%} -> {choice.second_doubtful:.1%} doubtful{other})"


def rival_note(rival: RivalChoice | None, reading: str = "a frame-by-frame reading", asked: bool = False) -> str:
    """What the summary line says of a reading that ran (``rival_reading``; ``reading`` names it),
    or, ``asked`` for, did not: the take was not doubtful enough for a second pass."""
    if rival is None:
        unread = reading.removeprefix("an ").removeprefix("a ")
        return f"; no {unread}: the take was not doubtful enough for a second pass" if asked else ""
    return f"; {counted(rival.markers, 'marker')}' labels from {reading}" if rival.markers else (
        f"; {reading} changed no label")
