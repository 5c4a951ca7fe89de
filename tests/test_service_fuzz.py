"""Schemathesis against the served OpenAPI schema: valid and invalid requests, never a 5xx."""

from __future__ import annotations

import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from schemathesis import GenerationMode
from service_fixtures import serving

from service.server.settings import Limits, Settings

EXAMPLES = 30  # per operation, valid and invalid requests mixed


@pytest.fixture(scope="module")
def schema(tmp_path_factory):
    db = tmp_path_factory.mktemp("fuzz") / "jobs.db"
    with serving(Settings(db=f"sqlite:///{db}", limits=Limits(max_body_bytes=2**20, max_solve_frames=20))) as client:
        yield schemathesis.openapi.from_url(f"{client.base_url}/openapi.json")


def test_every_operation_answers_without_a_server_error(schema):
    operations = [result.ok() for result in schema.get_all_operations()]
    assert {f"{o.method.upper()} {o.path}" for o in operations} >= {
        "POST /v1/jobs", "GET /v1/jobs", "GET /v1/jobs/{job_id}", "DELETE /v1/jobs/{job_id}",
        "GET /v1/jobs/{job_id}/events", "GET /v1/jobs/{job_id}/result", "POST /v1/solve", "GET /v1/formulations",
        "GET /healthz", "GET /metrics",
    }
    failures = []
    for operation in operations:
        cases = operation.as_strategy(GenerationMode.POSITIVE) | operation.as_strategy(GenerationMode.NEGATIVE)

        @settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                  phases=[Phase.explicit, Phase.generate], suppress_health_check=list(HealthCheck))
        @given(case=cases)
        def call(case) -> None:
            response = case.call(timeout=30)
            if response.status_code >= 500:
                failures.append(f"{case.method} {case.formatted_path} -> {response.status_code}: {response.text[:200]}")

        call()
    assert not failures, "\n".join(failures[:10])
