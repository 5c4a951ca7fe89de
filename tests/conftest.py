"""Shared test set-up: test helpers importable, real data located beside the repo, and the
job store's database: SQLite, or a throwaway PostgreSQL cluster started for the session."""

import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from postgres_cluster import PostgresCluster, PostgresUnavailable  # noqa: E402  (importable once the path is set)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


@pytest.fixture(scope="session")
def postgres_cluster() -> Iterator[PostgresCluster]:
    """PostgreSQL on 127.0.0.1 for the whole run, stopped at its end; skips saying why it cannot start."""
    try:
        cluster = PostgresCluster()
    except PostgresUnavailable as reason:
        pytest.skip(f"PostgreSQL cannot start: {reason}")
    try:
        yield cluster
    finally:
        cluster.stop()


@pytest.fixture(scope="session")
def postgres_url(postgres_cluster: PostgresCluster) -> str:
    """A fresh database in the session's cluster: ``postgresql+psycopg://postgres@127.0.0.1:<port>/<name>``."""
    return postgres_cluster.database()


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def store_url(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> str:
    """A fresh, empty job store for the module, once on SQLite and once on PostgreSQL."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path_factory.mktemp('store') / 'jobs.db'}"
    return request.getfixturevalue("postgres_cluster").database()
