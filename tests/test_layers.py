"""The layering holds: the mathematics never imports the application, no import cycles,
no module over 300 lines.

Each check is a function of a root folder, run on the repository and, to show it can
fail, on a small tree written with a deliberate violation.
"""

from __future__ import annotations

import ast
from collections.abc import Container, Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("formulations", "service")
MAX_LINES = 300


def modules(root: Path) -> dict[str, Path]:
    """Dotted name -> file of every module under the packages; a package is its ``__init__``."""
    found = {}
    for package in PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def imported(name: str, path: Path, known: Container[str]) -> Iterator[str]:
    """Every module an ``import`` in the file names, at top level or inside a function.

    ``from pkg import name`` is ``pkg.name`` when that is a module, else ``pkg``; a relative
    import is resolved against the module's own package.
    """
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            source = _from_source(node, package)
            for alias in node.names:
                yield f"{source}.{alias.name}" if f"{source}.{alias.name}" in known else source


def _from_source(node: ast.ImportFrom, package: list[str]) -> str:
    """The absolute name of ``from X import ...``: ``from ..a`` in ``p.q.m`` is ``p.a``."""
    if not node.level:
        return node.module or ""
    base = package[: len(package) - node.level + 1]
    return ".".join([*base, node.module] if node.module else base)


def service_imports_in_formulations(root: Path) -> list[str]:
    """``module: imported module`` for every import of ``service`` under formulations/."""
    known = modules(root)
    return sorted({
        f"{name}: {target}"
        for name, path in known.items() if name.split(".")[0] == "formulations"
        for target in imported(name, path, known) if target.split(".")[0] == "service"
    })


def import_graph(root: Path) -> dict[str, set[str]]:
    """Module -> the modules of formulations/ and service/ it imports (itself excluded)."""
    known = modules(root)
    return {name: {t for t in imported(name, path, known) if t in known and t != name} for name, path in known.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str]:
    """One import cycle as ``[a, b, ..., a]``, or [] if the graph is acyclic (depth-first search)."""
    done: set[str] = set()
    path: list[str] = []

    def visit(node: str) -> list[str]:
        if node in path:
            return path[path.index(node):] + [node]
        if node in done:
            return []
        path.append(node)
        for target in sorted(graph[node]):
            if cycle := visit(target):
                return cycle
        path.pop()
        done.add(node)
        return []

    for start in sorted(graph):
        if cycle := visit(start):
            return cycle
    return []


def long_modules(root: Path) -> list[str]:
    """``file: lines`` for every module over ``MAX_LINES`` lines."""
    counts = {path: len(path.read_text().splitlines()) for path in modules(root).values()}
    return [f"{path.relative_to(root)}: {n}" for path, n in counts.items() if n > MAX_LINES]


def test_formulations_never_import_service() -> None:
    assert service_imports_in_formulations(ROOT) == []


def test_no_import_cycle() -> None:
    cycle = find_cycle(import_graph(ROOT))
    assert not cycle, "import cycle: " + " -> ".join(cycle)


def test_no_module_over_300_lines() -> None:
    assert long_modules(ROOT) == []


def test_the_repository_is_what_the_checks_read() -> None:
    graph = import_graph(ROOT)
    assert len(graph) > 100
    assert "formulations.window.problem" in graph["formulations.window.build"]
    assert "service.io.formats" in graph["service.server.results"]  # from service.io.formats import write_labeled


def _tree(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


@pytest.mark.parametrize("statement", [
    "import service.io.recording",
    "from service.io import recording",
    "def late():\n    from service.io.recording import Recording\n",
])
def test_an_import_of_service_from_formulations_fails(tmp_path: Path, statement: str) -> None:
    root = _tree(tmp_path, {"formulations/__init__.py": "", "formulations/maths.py": statement,
                            "service/__init__.py": "", "service/io/recording.py": ""})
    assert service_imports_in_formulations(root) == ["formulations.maths: service.io.recording"]


CYCLE_THROUGH_A_FUNCTION = {
    "formulations/__init__.py": "",
    "formulations/a.py": "from formulations.b import thing\n",
    "formulations/b.py": "def thing():\n    from service.c import other\n",
    "service/__init__.py": "",
    "service/c.py": "from formulations import a\n",
}
CYCLE_THROUGH_RELATIVE_IMPORTS = {
    "service/__init__.py": "",
    "service/io/__init__.py": "from . import reader\n",
    "service/io/reader.py": "from ..shared import tools\n",
    "service/shared/__init__.py": "",
    "service/shared/tools.py": "from service.io import reader\n",
}


@pytest.mark.parametrize("files, cycle", [
    (CYCLE_THROUGH_A_FUNCTION, ["formulations.a", "formulations.b", "service.c", "formulations.a"]),
    (CYCLE_THROUGH_RELATIVE_IMPORTS, ["service.io.reader", "service.shared.tools", "service.io.reader"]),
], ids=["function-level", "relative"])
def test_an_import_cycle_fails(tmp_path: Path, files: dict[str, str], cycle: list[str]) -> None:
    assert find_cycle(import_graph(_tree(tmp_path, files))) == cycle


def test_relative_imports_are_resolved(tmp_path: Path) -> None:
    graph = import_graph(_tree(tmp_path, CYCLE_THROUGH_RELATIVE_IMPORTS))
    assert graph["service.io"] == {"service.io.reader"}  # from . import reader, in a package's __init__
    assert graph["service.io.reader"] == {"service.shared.tools"}  # from ..shared import tools


def test_an_acyclic_tree_passes(tmp_path: Path) -> None:
    root = _tree(tmp_path, {"formulations/__init__.py": "", "formulations/a.py": "import formulations.b\n",
                            "formulations/b.py": "import numpy\n", "service/__init__.py": "",
                            "service/c.py": "from formulations.a import x\n"})
    assert find_cycle(import_graph(root)) == []
    assert service_imports_in_formulations(root) == []


def test_a_long_module_fails(tmp_path: Path) -> None:
    root = _tree(tmp_path, {"formulations/__init__.py": "", "formulations/short.py": "x = 1\n" * MAX_LINES,
                            "service/__init__.py": "", "service/long.py": "x = 1\n" * (MAX_LINES + 1)})
    assert long_modules(root) == [f"service/long.py: {MAX_LINES + 1}"]
