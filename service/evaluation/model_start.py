"""A cloud scenario labeled from a subject model: the labeler gets no labeled frame.

The truth is cut to the markers the model knows (``check_shared_names`` refuses another
marker set), simulated as usual, and labeled under the model's names; the labels are then
put back in the truth's order, so the scores are those of ``label_scores``, and the truth
serves only for scoring.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from formulations.methods.formulation import Formulation
from formulations.subject.model import SubjectModel
from service.capture.capture import Capture
from service.capture.model_input import check_shared_names, model_names
from service.errors import InputError
from service.evaluation.cloud import Evaluation
from service.evaluation.scenario import Scenario
from service.evaluation.scores import label_scores
from service.evaluation.simulate_cloud import simulate_cloud
from service.io.recording import LabeledTrajectories, Recording
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.loop import Progress


def evaluate_from_model(
    truth: Recording, scenario: Scenario, model: SubjectModel, formulation: str | dict | Formulation | None = None,
    progress: Progress | None = None, source: str = "trajectories",
) -> Evaluation:
    """Simulate ``scenario`` on the model's markers of ``truth``, label from ``model``, score.

    Raises:
        InputError: Another marker set, or ``unnamed_markers`` (nothing is labeled to leave
            markers unnamed from: the model names all it knows).
    """
    if scenario.unnamed_markers:
        raise InputError(f"unnamed_markers = {scenario.unnamed_markers} with a subject model: no frame is labeled, "
                         "the model names every marker it knows; leave unnamed_markers out")
    check_shared_names(truth.names, model, source)
    names = model_names(model)
    shared = [n for n in truth.names if n in names]
    columns = [truth.names.index(n) for n in shared]
    cut = Recording(shared, truth.positions[:, columns], truth.rate)
    simulated = simulate_cloud(cut, scenario)
    capture = Capture(names, np.full((len(names), 3), np.nan), cut.rate, points=simulated.cloud.points, model=model)
    start = time.perf_counter()
    labeling = CaptureLabeling(capture, scenario.labeling_options(formulation))
    labeled, windows = labeling.label(progress)
    seconds = time.perf_counter() - start
    result = _columns(labeled, [names.index(n) for n in shared])
    scores = label_scores(simulated, result, first_given=False)  # the model named frame 0 too: it is scored
    return Evaluation(simulated, result, windows, scores, seconds, labeling.formulation.name)


def _columns(result: LabeledTrajectories, columns: list[int]) -> LabeledTrajectories:
    """The labels of ``columns``, in that order."""
    return replace(
        result, names=[result.names[c] for c in columns], positions=result.positions[:, columns],
        occluded=result.occluded[:, columns], point_index=result.point_index[:, columns],
        filled=result.filled[:, columns] if result.filled.size else result.filled,
    )
