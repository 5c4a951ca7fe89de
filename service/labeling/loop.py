"""The window loop every association shares: window after window, resumable, timed, certified.

An association supplies only its per-window chain, as two steps in the style of cvxpy's
reductions (``apply`` gives the reduced problem and the data its ``invert`` needs):

    pose:    marker state, the window's frames  ->  WindowProblem, inverse data
    invert:  WindowSolution, inverse data       ->  WindowLabels (labels, fill, next state)

For the windows ``(t_k, l_k)`` of ``window_spans`` the loop carries the marker state
``s_{k+1} = invert(solve(pose(s_k, t_k, l_k)))``, from ``s_0`` of the labeled first frame,
or from a stored outcome's state when it resumes; that state is the whole of what one
window hands the next, so a resumed run gives exactly what an uninterrupted one would.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

import numpy as np

from formulations.confidence.trusted_shape import TrustedShape
from formulations.errors import FormulationError
from formulations.markers.state import MarkerState
from formulations.methods.formulation import Formulation
from formulations.window.problem import WindowProblem
from formulations.window.solution import WindowSolution
from service.errors import InputError
from service.labeling.confidence import IdentityCarry, window_confidence
from service.labeling.outcome import WindowOutcome
from service.labeling.spans import window_spans
from service.labeling.stats import DoubtCount, WindowStats

Inverse = TypeVar("Inverse")
Progress = Callable[[int, int], None]  # (windows done, windows)
Observer = Callable[[int, WindowProblem, WindowSolution], None]  # (template frame, problem, solution)


@dataclass(frozen=True)
class WindowLabels:
    """What inverting one window's solution gives; ``WindowOutcome`` documents the shapes."""

    state: MarkerState
    point_index: np.ndarray
    filled: np.ndarray
    views: np.ndarray | None = None
    positions: np.ndarray | None = None


class WindowChain(Protocol[Inverse]):
    """One association's per-window chain."""

    def pose(
        self, state: MarkerState, template: int, last: int, confidence: np.ndarray | None = None,
    ) -> tuple[WindowProblem, Inverse]:
        """The window problem of frames ``template+1 .. last`` from ``state`` at ``template``;
        ``confidence`` ``(N,)``: the probability that each marker's label there is right."""
        ...

    def invert(self, solution: WindowSolution, inverse: Inverse) -> WindowLabels:
        """The window's labels and the marker state at its last frame."""
        ...


def label_windows(
    chain: WindowChain[Any], formulation: Formulation, first: MarkerState, n_frames: int, window: int,
    after: WindowOutcome | None = None, progress: Progress | None = None, observer: Observer | None = None,
) -> Iterator[WindowOutcome]:
    """Each window's outcome as it is finished.

    Args:
        chain: The association's pose and invert steps.
        formulation: Solves each posed window.
        first: The marker state of the labeled first frame.
        n_frames, window: Frames of the capture, and per window (template included).
        after: The last finished window of an interrupted run: labeling resumes with the
            next window from its marker state.
        progress: Called with (windows done, windows) after each window.
        observer: Called with (template frame, problem, solution) after each window.
    """
    spans = window_spans(n_frames, window)
    state = first if after is None else after.state
    carry = _template_carry(first, after)
    for k in range(0 if after is None else after.index + 1, len(spans)):
        template, last = spans[k]
        began = time.perf_counter()
        problem, inverse = chain.pose(state, template, last, carry.confidence)
        prepared = time.perf_counter() - began
        solution = _solve(formulation, problem, template)
        labels = chain.invert(solution, inverse)
        judged = time.perf_counter()
        occluded = _occluded(labels)
        confidence, carry = window_confidence(problem, solution, labels.views, occluded, carry, state, labels.state)
        doubt = DoubtCount.of(confidence, occluded, time.perf_counter() - judged)
        stats = WindowStats.of(template, last, solution, prepared, time.perf_counter() - began, doubt)
        if observer:
            observer(template, problem, solution)
        if progress:
            progress(k + 1, len(spans))
        state = carry.forget_doubtful(labels.state)
        yield WindowOutcome(
            index=k, point_index=labels.point_index, filled=labels.filled, stats=stats, state=state,
            views=labels.views, positions=labels.positions, confidence=confidence, carry=carry.confidence,
            trusted_mean=carry.shape.distance_mean, trusted_var=carry.shape.distance_var,
        )


def _template_carry(first: MarkerState, after: WindowOutcome | None) -> IdentityCarry:
    """What the first window to label is carried on from: from the given first frame, every
    label trusted; after ``after``, its carry. An outcome stored before confidences existed
    hands on 1; one stored before trusted shapes, its state's shapes (what a marker trusted
    at its end would hand on)."""
    if after is None:
        return IdentityCarry.start(first)
    confidence = after.carry if after.carry is not None else np.ones(first.position.shape[0])
    if after.trusted_mean is None or after.trusted_var is None:
        return IdentityCarry(confidence, TrustedShape.of(after.state))
    return IdentityCarry(confidence, TrustedShape(after.trusted_mean, after.trusted_var))


def _occluded(labels: WindowLabels) -> np.ndarray:
    """``(M, N)`` markers the window left without a point (or, per camera, without a view)."""
    if labels.positions is not None:
        return np.isnan(labels.positions).any(axis=2)
    occluded: np.ndarray = labels.point_index < 0
    return occluded


def first_marker_state(names: list[str], first_frame: np.ndarray) -> MarkerState:
    """The marker state of the user's labeled first frame.

    Raises:
        InputError: Wrong shape, or a marker without a position.
    """
    first_frame = np.asarray(first_frame, dtype=float)
    if first_frame.shape != (len(names), 3):
        raise InputError(f"first frame must give (x, y, z) for each of the {len(names)} markers")
    bad = np.flatnonzero(~np.isfinite(first_frame).all(axis=1))
    if len(bad):
        raise InputError(f"marker '{names[bad[0]]}' has no position in the first frame")
    return MarkerState.from_first_frame(first_frame)


def _solve(formulation: Formulation, problem: WindowProblem, template: int) -> WindowSolution:
    """A formulation that cannot take this window is the user's choice to revisit: one line."""
    try:
        return formulation.solve(problem)
    except FormulationError as error:
        raise InputError(f"window from frame {template}: {error}") from None


def progress_after(progress: Progress | None, done: int) -> Progress | None:
    """``progress`` of a pass that follows ``done`` windows, counted with them."""
    if progress is None:
        return None
    report = progress  # bound here: mypy keeps the narrowing inside the closure
    return lambda k, n: report(done + k, done + n)
