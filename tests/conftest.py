"""Shared test set-up: test helpers importable, real data located beside the repo."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
