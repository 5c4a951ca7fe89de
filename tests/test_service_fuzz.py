"""Schemathesis against the served OpenAPI schema, on SQLite and on PostgreSQL: valid and invalid
requests, never a 5xx, every answer as the schema describes it (``bench/schemathesis_run.py``
runs the same with 200 cases per operation)."""

from __future__ import annotations

import pytest
from schema_fuzz import OPERATIONS, fuzz_failures, fuzz_schema
from service_fixtures import serving

from service.server.settings import Limits, Settings

EXAMPLES = 30  # per operation, valid and invalid requests mixed


@pytest.fixture(scope="module")
def served(store_url):
    with serving(Settings(db=store_url, limits=Limits(max_body_bytes=2**20, max_solve_frames=20))) as client:
        yield str(client.base_url)


def test_every_operation_answers_as_its_schema_says_and_never_with_a_server_error(served):
    tallies = fuzz_schema(served, EXAMPLES)
    assert set(tallies) >= OPERATIONS
    assert all(tally.cases > 0 for tally in tallies.values())
    failures = fuzz_failures(tallies)
    assert not failures, "\n".join(failures[:10])
