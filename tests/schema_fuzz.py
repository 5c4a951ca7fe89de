"""Schemathesis over every operation of a served OpenAPI schema: valid and invalid requests,
each answer checked against the schema; the cases and status classes counted per operation."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from schemathesis import Case, GenerationMode
from schemathesis.checks import content_type_conformance, not_a_server_error, response_schema_conformance
from schemathesis.core.failures import Failure, FailureGroup

# A 5xx, a body the operation's response schema does not allow, a content type it does not declare.
CHECKS = [not_a_server_error, response_schema_conformance, content_type_conformance]
OPERATIONS = {
    "POST /v1/jobs", "GET /v1/jobs", "GET /v1/jobs/{job_id}", "DELETE /v1/jobs/{job_id}",
    "GET /v1/jobs/{job_id}/events", "GET /v1/jobs/{job_id}/result", "POST /v1/solve", "GET /v1/formulations",
    "GET /healthz", "GET /metrics",
}


@dataclass
class OperationTally:
    """One operation's cases, their answers by status class ("2xx", "4xx", ...) and the failed checks."""

    cases: int = 0
    statuses: Counter[str] = field(default_factory=Counter)
    failures: list[str] = field(default_factory=list)


def fuzz_schema(base_url: str, examples: int) -> dict[str, OperationTally]:
    """Up to ``examples`` generated cases per operation (Hypothesis stops early once an operation's
    inputs are exhausted), positive and negative mixed, each checked with ``CHECKS``."""
    schema = schemathesis.openapi.from_url(f"{base_url}/openapi.json")
    tallies: dict[str, OperationTally] = {}
    for result in schema.get_all_operations():
        operation = result.ok()
        tally = tallies.setdefault(f"{operation.method.upper()} {operation.path}", OperationTally())
        cases = operation.as_strategy(GenerationMode.POSITIVE) | operation.as_strategy(GenerationMode.NEGATIVE)
        settings(max_examples=examples, derandomize=True, deadline=None, database=None,
                 phases=[Phase.explicit, Phase.generate], suppress_health_check=list(HealthCheck))(
            given(case=cases)(_checked_call(base_url, tally)))()
    return tallies


def _checked_call(base_url: str, tally: OperationTally) -> Callable[[Case], None]:
    """Send one case, count its status class, keep any failed check in ``tally``."""

    def call(case: Case) -> None:
        response = case.call(base_url=base_url, timeout=30)
        tally.cases += 1
        tally.statuses[f"{response.status_code // 100}xx"] += 1
        try:
            case.validate_response(response, checks=CHECKS)
        except (Failure, FailureGroup) as failure:
            tally.failures.append(f"{case.method} {case.formatted_path} -> {response.status_code}: "
                                  f"{str(failure).strip()[:300]}")

    return call


def fuzz_failures(tallies: dict[str, OperationTally]) -> list[str]:
    """Every failed check, and every 5xx, over all operations."""
    return [failure for tally in tallies.values() for failure in tally.failures]
