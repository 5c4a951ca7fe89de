"""The fraction of integral windows and the gaps may not get worse than recorded."""

import json

import pytest

from integrality_corpus import FIXTURE, corpora, measure

RECORDED = json.loads(FIXTURE.read_text())
CORPORA = corpora()


@pytest.mark.parametrize("name", sorted(RECORDED))
def test_integrality_is_no_worse_than_recorded(name):
    now, then = measure(CORPORA[name]), RECORDED[name]
    assert now["windows"] == then["windows"]
    assert now["integral_fraction"] >= then["integral_fraction"] - 1e-12
    assert now["gap_median"] <= then["gap_median"] + 1e-9
    assert now["gap_max"] <= then["gap_max"] + 1e-9
