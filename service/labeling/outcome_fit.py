"""Whether stored window outcomes are this labeling's, before anything is built on them.

``CaptureLabeling.windows(after=...)`` resumes from a stored outcome and ``result`` assembles
stored ones. An outcome of another window size puts its marker state at the wrong template
(labels silently wrong), one of another capture fails deep inside numpy or, for a take of the
same markers and length, builds on that take's marker states; all are the caller's mistake,
said in one line. Outcomes carry the digest of their capture (``capture.fingerprint``);
one stored before they did (``labeling`` None) is checked by its span and markers only.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import replace

from service.errors import InputError
from service.labeling.outcome import WindowOutcome


def check_resumable(outcome: WindowOutcome, spans: list[tuple[int, int]], markers: int, labeling: str) -> None:
    """Raise ``InputError`` unless ``outcome`` is window ``outcome.index`` of a labeling whose
    windows span ``spans`` (template, last), whose state holds ``markers`` markers and whose
    capture's digest is ``labeling``."""
    span = (outcome.stats.template, outcome.stats.last)
    if not 0 <= outcome.index < len(spans) or spans[outcome.index] != span:
        raise InputError(
            f"window {outcome.index} (frames {span[0]}-{span[1]}) is not a window of this labeling "
            f"({len(spans)} windows, frames {spans[0][0]}-{spans[-1][1]}): stored with another window size or capture?"
        )
    held = len(outcome.state.position)
    if held != markers:
        raise InputError(f"window {outcome.index} holds the state of {held} markers; this capture labels {markers}")
    if outcome.labeling is not None and outcome.labeling != labeling:
        raise InputError(f"window {outcome.index} was labeled from another capture (its points, names, first frame "
                         "or rate differ): resume a labeling only with its own capture's outcomes")


def check_outcomes(outcomes: Sequence[WindowOutcome], spans: list[tuple[int, int]], markers: int, labeling: str) -> None:
    """Raise ``InputError`` unless ``outcomes`` are this labeling's windows 0, 1, ... in order."""
    indices = [outcome.index for outcome in outcomes]
    if indices != list(range(len(outcomes))) or len(outcomes) > len(spans):
        shown = ", ".join(map(str, indices[:8])) + (" ..." if len(indices) > 8 else "")
        raise InputError(f"outcomes must be windows 0, 1, ... in order, at most {len(spans)}; got windows {shown}")
    for outcome in outcomes:
        check_resumable(outcome, spans, markers, labeling)


def stamped(outcomes: Iterable[WindowOutcome], labeling: str) -> Iterator[WindowOutcome]:
    """``outcomes`` marked as windows of the capture whose digest is ``labeling``."""
    return (replace(outcome, labeling=labeling) for outcome in outcomes)
