"""A joint whose centre lies beyond a limb's reach of every marker of one of its segments is
named (``model`` printed such a joint, pelvis to upper arm, as the subject's without a word)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from test_subject_model import chain
from typer.testing import CliRunner

from formulations.subject.far_joints import far_joints
from formulations.subject.fit import fit_subject
from formulations.subject.model import Joint, Segment, SubjectModel
from service.cli.app import app
from service.io.formats import write_labeled
from service.io.recording import LabeledTrajectories

CMU_135_02 = DATA / "c3d_mocaprecovery_cmu_hdm05_numediart" / "135_02.c3d"
SQUARE = [[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]]


def _model(centre_in_a: list[float]) -> SubjectModel:
    segments = [Segment(name, [f"{name}{k}" for k in range(3)], SQUARE, [1.0] * 3) for name in ("A", "B")]
    return SubjectModel(segments, [Joint("AB", ("A", "B"), (centre_in_a, [0.0, 0.0, -50.0]), 2.0)], [], [])


def test_a_centre_past_a_limbs_reach_is_named_and_a_near_one_is_not() -> None:
    [far] = far_joints(_model([0.0, 0.0, 520.0]))
    assert (far.joint, far.segment) == ("AB", "A") and np.isclose(far.apart_mm, 520.0)
    assert far_joints(_model([0.0, 0.0, 380.0])) == []


def test_a_fitted_chain_has_none_and_the_command_says_nothing(tmp_path: Path) -> None:
    names, positions, _ = chain(3)
    assert far_joints(fit_subject(names, positions).model) == []
    take = tmp_path / "take.trc"
    write_labeled(take, LabeledTrajectories(names, positions, np.zeros(positions.shape[:2], bool), 100.0))
    result = CliRunner().invoke(app, ["-q", "model", str(take), "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 0 and "no body joint is" not in result.output


@pytest.mark.skipif(not CMU_135_02.exists(), reason="needs ../shared/data")
def test_cmu_135_02s_first_600_frames_join_the_pelvis_to_an_arm_and_are_told_so(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["-q", "model", str(CMU_135_02), "--end", "600", "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 0
    assert "male:LFWT-male:LUPA (509 mm from male:LFWT)" in result.output
