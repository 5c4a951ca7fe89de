"""A throwaway PostgreSQL cluster on loopback, for running the store's tests on PostgreSQL too.

``initdb`` into a fresh temporary folder, ``pg_ctl start`` on 127.0.0.1 at a free port with
trust authentication, one new database per store, ``pg_ctl stop`` and the folder removed at
the end. PostgreSQL refuses to run as root, so as root the cluster belongs to the ``postgres``
user of Debian's package (or ``nobody``) and every command runs through ``runuser``.
"""

from __future__ import annotations

import glob
import os
import pwd
import shutil
import socket
import subprocess
import tempfile
from pathlib import Path


class PostgresUnavailable(Exception):
    """PostgreSQL cannot start here; the message says why."""


def _binaries() -> Path:
    """The folder holding ``initdb`` and ``pg_ctl``: on PATH, else Debian's /usr/lib/postgresql/<n>/bin."""
    on_path = shutil.which("initdb")
    found = [on_path] if on_path else sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"))
    if not found or not shutil.which("pg_ctl", path=str(Path(found[-1]).parent)):
        raise PostgresUnavailable("PostgreSQL binaries not found (install Debian's postgresql)")
    return Path(found[-1]).parent


def _runner() -> tuple[list[str], pwd.struct_passwd | None]:
    """The command prefix and the user the cluster runs as: the caller, unless root."""
    if os.geteuid() != 0:
        return [], None
    for name in ("postgres", "nobody"):
        try:
            return ["runuser", "-u", name, "--"], pwd.getpwnam(name)
        except KeyError:
            continue
    raise PostgresUnavailable("running as root with neither a 'postgres' nor a 'nobody' user to run PostgreSQL")


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class PostgresCluster:
    """A started cluster; ``database()`` makes a fresh database and gives its SQLAlchemy URL."""

    def __init__(self) -> None:
        try:
            import psycopg  # noqa: F401  (the driver the URLs name)
        except ImportError:
            raise PostgresUnavailable("psycopg is not installed (pip install 'psycopg[binary]')") from None
        binaries, (prefix, user) = _binaries(), _runner()
        self.folder = Path(tempfile.mkdtemp(prefix="markerflow-pg-"))
        if user is not None:
            os.chown(self.folder, user.pw_uid, user.pw_gid)
        self._pg_ctl = [*prefix, str(binaries / "pg_ctl"), "-D", str(self.folder / "data")]
        self.port = _free_port()
        self._run([*prefix, str(binaries / "initdb"), "-D", str(self.folder / "data"), "-U", "postgres",
                   "--auth=trust", "--no-sync", "-E", "UTF8"], "initdb")
        options = (f"-c listen_addresses=127.0.0.1 -c port={self.port} -c unix_socket_directories={self.folder} "
                   "-c fsync=off -c max_connections=200")
        self._run([*self._pg_ctl, "-w", "-t", "60", "-l", str(self.folder / "server.log"), "-o", options, "start"],
                  "pg_ctl start")
        self._databases = 0

    def _run(self, command: list[str], what: str) -> None:
        done = subprocess.run(command, capture_output=True, text=True, timeout=120, cwd=self.folder)
        if done.returncode != 0:
            log = self.folder / "server.log"
            tail = log.read_text()[-1000:] if log.exists() else ""
            shutil.rmtree(self.folder, ignore_errors=True)
            raise PostgresUnavailable(f"{what} failed: {(done.stderr or done.stdout).strip()[-500:]} {tail}".strip())

    def database(self) -> str:
        """A new empty database: its ``postgresql+psycopg://`` URL."""
        import psycopg

        self._databases += 1
        name = f"store_{self._databases}"
        with psycopg.connect(f"host=127.0.0.1 port={self.port} user=postgres dbname=postgres", autocommit=True) as db:
            db.execute(f"CREATE DATABASE {name}")
        return f"postgresql+psycopg://postgres@127.0.0.1:{self.port}/{name}"

    def stop(self) -> None:
        """Stop at once (open connections are cut) and remove the folder."""
        subprocess.run([*self._pg_ctl, "-m", "immediate", "-w", "stop"], capture_output=True, timeout=60,
                       cwd=self.folder)
        shutil.rmtree(self.folder, ignore_errors=True)
