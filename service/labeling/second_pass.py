"""Label a take again with the distance spreads its first labeling measured, and keep the
labeling that bends the take's rigid pairs least off the labeled first frame.

The first pass starts every marker-neighbour distance from the same prior spread
(``MarkerState``); the second starts from the spreads the first pass's labels show over the
whole take (``formulations.markers.take_spread``). That is right where the first pass was
mostly right, and wrong where it was not: the spreads of mislabeled markers are those of
the points they took.

Which pass to keep is decided by the first frame, which the user labeled: each pass's
labels are measured against its distances between rigid mates
(``formulations.markers.first_frame_shape``), and the second is kept when it agrees better.
The labels' own doubt was the judge before, and a poor one: each pass's confidence is
conditional on the spreads it started from, so a second pass from wider spreads doubts the
same right labels more (CMU 135_02, hard preset, seed 0: 83.6 % right and 20.8 % doubtful
against 95.6 % right and 25.2 % doubtful; the doubt kept the first). Both passes run to
the end and kept by each judge (``bench/pass_choice.py``, lp-l1, command in docs/track.md): over the 31 of 44 runs of 11
takes under four matrix conditions (seed 0, 600 frames) where a second pass runs, the mean
accuracy kept is 96.69 % by the doubt, 96.92 % by the first frame, 96.96 % keeping the better
pass each time; over the hard preset's 9 runs (3 takes, seeds 0-2) 88.65 %, 89.98 % and 89.98 %.

Where the passes disagree, each is often right somewhere the other is not, so the pass kept
is kept whole only where the other does no better: the labels they give differently fall
into events that share no point, and each event takes the labels of the pass that bends its
rigid pairs less off the first frame (``formulations.markers.pass_merge``).

The kept windows' confidences are then judged with the other pass's labels
(``formulations.confidence.two_readings``): a label both give keeps the surer confidence, a
label the other pass reads otherwise gets at most one minus the other's.

The doubt still says whether a second pass is worth running: not when the first pass is no
more doubtful than a take ``track`` does not warn about (``DOUBTFUL_WARNING``, 2 %), so a
clean take costs one pass; nor when three labels in four or more are doubtful
(``MOSTLY_DOUBTFUL``): the spreads would then be mostly those of points the markers took
(the wheelchair racing take at 2 and 4 mm noise, 85-96 % doubtful: the second pass lost up
to 15 points).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from formulations.confidence.two_readings import agreed_confidence
from formulations.markers.first_frame_handedness import first_frame_judges
from formulations.markers.first_frame_shape import disagreement
from formulations.markers.pass_merge import labels_taken
from formulations.markers.state import MarkerState
from formulations.markers.take_spread import with_take_spread
from formulations.methods.formulation import Formulation
from service.io.recording import LabeledTrajectories
from service.labeling.loop import Progress, WindowChain, label_windows
from service.labeling.merged_windows import merged_windows
from service.labeling.outcome import WindowOutcome
from service.labeling.stats import DOUBTFUL_WARNING, doubtful_labels

MOSTLY_DOUBTFUL = 0.75  # three labels in four doubtful: the spreads are mostly wrong ones (module docstring)

Stop = Callable[[], bool]  # asked between windows: True abandons the pass
Labels = Callable[[list[WindowOutcome]], LabeledTrajectories]  # a pass's labels, tracks extended


@dataclass(frozen=True)
class PassChoice:
    """Which labeling was kept.

    Attributes:
        first_doubtful, second_doubtful: Share of each pass's labels that are doubtful; None
            for a second pass not run.
        first_off_mm, second_off_mm: Each pass's disagreement with the first frame's rigid
            pairs (``first_frame_disagreement``, mm); None for a second pass not run.
        kept: 1 or 2: the pass whose windows (and certificates) are kept.
        taken_from_other: Markers with labels from the other pass instead, in the events
            where the passes disagree and the other bends those markers' rigid pairs less
            (``formulations.markers.pass_merge``).
    """

    first_doubtful: float
    second_doubtful: float | None
    kept: int
    first_off_mm: float | None = None
    second_off_mm: float | None = None
    taken_from_other: int = 0

    def to_dict(self) -> dict:
        return {"first_doubtful": self.first_doubtful, "second_doubtful": self.second_doubtful, "kept": self.kept,
                "first_off_mm": self.first_off_mm, "second_off_mm": self.second_off_mm,
                "taken_from_other": self.taken_from_other}


def doubtful_share(outcomes: list[WindowOutcome]) -> float:
    """Doubtful labels / labels over the windows (0 with no label)."""
    labels = sum(o.stats.labels for o in outcomes)
    return sum(o.stats.doubtful for o in outcomes) / labels if labels else 0.0


def second_pass_runs(outcomes: list[WindowOutcome], bar: float = DOUBTFUL_WARNING) -> bool:
    """Whether ``second_pass`` labels the take of first-pass ``outcomes`` again: a share of
    doubtful labels above a clean take's (``bar``) and below a mostly wrong one's (module doc)."""
    return bar < doubtful_share(outcomes) <= MOSTLY_DOUBTFUL


def second_pass(
    chain: WindowChain, formulation: Formulation, first: MarkerState, frames: int, window: int,
    outcomes: list[WindowOutcome], labels: Labels, progress: Progress | None = None,
    stop: Stop | None = None, learned: Labels | None = None,
) -> tuple[list[WindowOutcome], PassChoice] | None:
    """The windows to keep (``outcomes`` itself when no second pass runs, else the kept
    pass's, with the markers the other pass labels better taken from it: ``pass_merge``;
    each confidence judged with the other pass's: ``with_other_reading``) and the choice;
    None when ``stop`` asked to abandon the pass.

    Args:
        chain, formulation, frames, window: As the first pass was labeled.
        first: The first pass's first marker state (its positions: the labeled first frame).
        outcomes: The first pass's windows.
        labels: Gives a pass's labels, tracks extended, as the merge takes them (the windows'
            own: no take-wide repair); asked only when a second pass runs (a clean take is not
            assembled twice).
        learned: Gives the first pass's labels the second pass learns its spreads from
            (``labels`` when None): repaired ones, where exchanges the take-wide repairs give
            back no longer widen their pairs.
    """
    before = doubtful_share(outcomes)
    if not second_pass_runs(outcomes):
        return outcomes, PassChoice(before, None, 1)
    labeled = judged_part(labels(outcomes))
    taught = labeled if learned is None else judged_part(learned(outcomes))
    second: list[WindowOutcome] = []
    for outcome in label_windows(chain, formulation, with_take_spread(first, taught.positions), frames, window, None, progress):
        second.append(outcome)
        if stop is not None and stop():
            return None
    relabeled = judged_part(labels(second))
    kept, taken, off = judged_passes(labeled, relabeled, first)
    mine, theirs = (second, outcomes) if kept == 2 else (outcomes, second)
    first_off, second_off = (None if np.isnan(v) else float(v) for v in off)
    choice = PassChoice(before, doubtful_share(second), kept, first_off, second_off, int(taken.any(axis=0).sum()))
    return merged_readings(mine, theirs, taken), choice


def merged_readings(mine: list[WindowOutcome], theirs: list[WindowOutcome], taken: np.ndarray) -> list[WindowOutcome]:
    """``mine`` with the labels ``taken`` (``(F, N)`` bool over the take's frames) as in ``theirs``
    (``merged_windows``), each label's confidence judged with the other reading's
    (``with_other_reading``). Both read the same windows of one take."""
    windows = with_other_reading(mine, theirs)
    if not taken.any():  # nothing from the other reading: its confidences need no second judging
        return windows
    return merged_windows(windows, with_other_reading(theirs, mine), taken)


def judged_part(labels: LabeledTrajectories) -> LabeledTrajectories:
    """What the spreads and the judges read of a pass's labels: positions and point indices
    (its fill and confidences, 1.3 kB a frame at 41 markers, are not kept beside the other pass's)."""
    return LabeledTrajectories(labels.names, labels.positions, labels.occluded, labels.rate, labels.point_index)


def judged_passes(
    first_labels: LabeledTrajectories, second_labels: LabeledTrajectories, first: MarkerState,
) -> tuple[int, np.ndarray, np.ndarray]:
    """Which pass's windows are kept (1 or 2: the one whose rigid pairs agree better with the
    first frame, ``first_frame_shape``), the ``(N,)`` markers to take from the other
    (``pass_merge``), and each pass's disagreement (mm). Both judges read one computation
    of the passes' offsets off the first frame."""
    capped, judged, flips = first_frame_judges([first_labels.positions, second_labels.positions], first.position,
                                               first.neighbours)
    off = disagreement(capped, judged)
    # NaN (no rigid pair labeled together) compares False: the first pass stays.
    kept = 2 if off[1] < off[0] else 1
    order = [1, 0] if kept == 2 else [0, 1]
    points = (first_labels.point_index, second_labels.point_index)
    taken = labels_taken((points[order[0]], points[order[1]]), capped[order], judged, flips=flips[order])
    return kept, taken, off


def with_other_reading(kept: list[WindowOutcome], other: list[WindowOutcome]) -> list[WindowOutcome]:
    """The kept pass's windows, each label's confidence judged with the other pass's
    (``formulations.confidence.two_readings``) and the windows' doubt counted again. Both
    passes label the same windows (one take, one window length)."""
    judged = []
    for mine, theirs in zip(kept, other, strict=True):
        if mine.confidence is None or theirs.confidence is None:
            judged.append(mine)
            continue
        confidence = agreed_confidence(mine.confidence, mine.point_index, theirs.confidence, theirs.point_index)
        doubtful = int(doubtful_labels(confidence, mine.point_index < 0).sum())
        judged.append(replace(mine, confidence=confidence, stats=replace(mine.stats, doubtful=doubtful)))
    return judged
