"""Label a take again with the distance spreads its first labeling measured, and keep the
labeling the labeler is surer of.

The first pass starts every marker-neighbour distance from the same prior spread
(``MarkerState``); the second starts from the spreads the first pass's labels show over the
whole take (``formulations.markers.take_spread``). That is right where the first pass was
mostly right, and wrong where it was not: the spreads of mislabeled markers are those of
the points they took. Which pass to keep is decided by the labels' own confidence: the
second is kept when a smaller share of its labels is doubtful (``DOUBTFUL_BELOW``).
When the first pass is no more doubtful than a take ``track`` does not warn about
(``DOUBTFUL_WARNING``, 2 %), the second is not run: a clean take costs one pass. Nor is it
when three labels in four or more are doubtful (``MOSTLY_DOUBTFUL``): the spreads would
then be mostly those of points the markers took, and with both passes near all-doubtful
the share no longer tells them apart. A second pass stops as soon as it cannot be kept: when
its doubtful labels so far, over its labels so far plus one label per marker in every frame
left, are already no fewer than the first pass's share (the final share can only be
higher), it is abandoned with the first pass kept, the same choice a full run makes (the
real racing and floor-rolling takes: 24.4 -> 20.4 s and 63.5 -> 55.4 s, labels unchanged).
On the seed-0 accuracy matrix the rows above a half
were Hamner running at 4 mm noise (52 % -> 50 % doubtful, 95.6 -> 98.1 % correct) and the
wheelchair racing take (85-96 % doubtful, both passes; 76.7 -> 76.0, 73.6 -> 68.6 and
58.5 -> 43.3 % correct): the bound lies between them, chosen on that matrix.

Measured (README, "Second pass"): the real tennis serve goes from 96.2 % to 99.9 % correct
(doubtful 8.9 % -> 3.3 %); on the real racing and floor-rolling takes the second pass is
more doubtful (18.5 -> 28 %, 37 -> 61 %), is less accurate, and is not kept. Over the
accuracy matrix the doubt is a weaker judge: seed 0, 85 rows, one pass 96.12 %, both
96.23 % (95.98 % before the bound on doubt); seeds 1-2, 80 rows, 98.45 -> 98.63 %.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from formulations.markers.state import MarkerState
from formulations.markers.take_spread import with_take_spread
from formulations.methods.formulation import Formulation
from service.labeling.loop import Progress, WindowChain, label_windows
from service.labeling.outcome import WindowOutcome
from service.labeling.stats import DOUBTFUL_WARNING

MOSTLY_DOUBTFUL = 0.75  # three labels in four doubtful: the share no longer judges (module docstring)

Stop = Callable[[], bool]  # asked between windows: True abandons the pass


@dataclass(frozen=True)
class PassChoice:
    """Which labeling was kept.

    Attributes:
        first_doubtful, second_doubtful: Share of each pass's labels that are doubtful
            (the second's over the windows it labeled); None for a second pass not run.
        kept: 1 or 2.
        second_complete: False when the second pass stopped once it could not be kept.
    """

    first_doubtful: float
    second_doubtful: float | None
    kept: int
    second_complete: bool = True

    def to_dict(self) -> dict:
        return {"first_doubtful": self.first_doubtful, "second_doubtful": self.second_doubtful, "kept": self.kept,
                "second_complete": self.second_complete}


def doubtful_share(outcomes: list[WindowOutcome]) -> float:
    """Doubtful labels / labels over the windows (0 with no label)."""
    labels = sum(o.stats.labels for o in outcomes)
    return sum(o.stats.doubtful for o in outcomes) / labels if labels else 0.0


def second_pass(
    chain: WindowChain, formulation: Formulation, first: MarkerState, frames: int, window: int,
    outcomes: list[WindowOutcome], positions: Callable[[], np.ndarray], progress: Progress | None = None,
    stop: Stop | None = None,
) -> tuple[list[WindowOutcome], PassChoice] | None:
    """The windows to keep (``outcomes`` or the second pass's) and the choice; None when
    ``stop`` asked to abandon the pass.

    Args:
        chain, formulation, frames, window: As the first pass was labeled.
        first: The first pass's first marker state.
        outcomes: The first pass's windows.
        positions: Gives the ``(F, N, 3)`` labeled positions of ``outcomes``, NaN where a
            marker has none; asked only when a second pass runs (a clean take is not
            assembled twice).
    """
    before = doubtful_share(outcomes)
    if not DOUBTFUL_WARNING < before <= MOSTLY_DOUBTFUL:
        return outcomes, PassChoice(before, None, 1)
    second: list[WindowOutcome] = []
    for outcome in label_windows(chain, formulation, with_take_spread(first, positions()), frames, window, None, progress):
        second.append(outcome)
        if stop is not None and stop():
            return None
        if _cannot_be_kept(second, before, len(first.position) * (frames - 1 - outcome.stats.last)):
            return outcomes, PassChoice(before, doubtful_share(second), 1, second_complete=False)
    after = doubtful_share(second)
    return (second, PassChoice(before, after, 2)) if after < before else (outcomes, PassChoice(before, after, 1))


def _cannot_be_kept(second: list[WindowOutcome], before: float, labels_left: int) -> bool:
    """True when the second pass's final share cannot fall below ``before``: its doubtful
    labels so far over its labels so far plus the most labels the frames left can hold."""
    labels = sum(o.stats.labels for o in second) + labels_left
    return labels > 0 and sum(o.stats.doubtful for o in second) >= before * labels
