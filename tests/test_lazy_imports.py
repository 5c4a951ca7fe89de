"""The command line starts without loading the labeler: ``service`` loads its names on first use."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _loaded_after(code: str) -> set[str]:
    done = subprocess.run([sys.executable, "-c", f"{code}\nimport sys\nprint(' '.join(sys.modules))"],
                          capture_output=True, text=True, cwd=ROOT, check=True)
    return set(done.stdout.split())


def test_the_command_line_does_not_load_the_labeler_to_start():
    assert "service.labeling.capture_labeling" not in _loaded_after("import service.cli.app")


def test_the_package_names_load_on_first_use():
    import service

    assert "CaptureLabeling" in dir(service)
    assert service.CaptureLabeling.__module__ == "service.labeling.capture_labeling"
    assert "service.labeling.capture_labeling" in _loaded_after("from service import CaptureLabeling")
