"""The application around the mathematics: captures, files, labeling, evaluation, CLI and HTTP service.

    from service import Capture, LabelingOptions, CaptureLabeling, write_labeled

    capture = Capture(names, first_frame, rate=120.0, points=frames)
    labels, windows = CaptureLabeling(capture, LabelingOptions(formulation="lp-l1")).label()
    write_labeled("take_labeled.c3d", labels)
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the names below, for type checkers; at run time they load on first use
    from service.capture.capture import Capture, LabelingOptions
    from service.capture.document import CaptureDocument
    from service.errors import InputError
    from service.io.calibration import load_calibration
    from service.io.formats import read_labeled, write_labeled
    from service.io.recording import LabeledTrajectories, Recording, UnlabeledCloud
    from service.labeling.capture_labeling import CaptureLabeling
    from service.labeling.outcome import WindowOutcome

# Loaded on first use (PEP 562), so that ``markerflow --help`` and commands that do not label
# (boxes, mot-eval, serve) do not import the whole labeler first (about a second).
_WHERE = {
    "Capture": "service.capture.capture", "LabelingOptions": "service.capture.capture",
    "CaptureDocument": "service.capture.document", "InputError": "service.errors",
    "load_calibration": "service.io.calibration", "read_labeled": "service.io.formats",
    "write_labeled": "service.io.formats", "LabeledTrajectories": "service.io.recording",
    "Recording": "service.io.recording", "UnlabeledCloud": "service.io.recording",
    "CaptureLabeling": "service.labeling.capture_labeling", "WindowOutcome": "service.labeling.outcome",
}

__all__ = [
    "Capture", "CaptureDocument", "CaptureLabeling", "InputError", "LabeledTrajectories", "LabelingOptions",
    "Recording", "UnlabeledCloud", "WindowOutcome", "load_calibration", "read_labeled", "write_labeled",
]


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module 'service' has no attribute '{name}'")
    return getattr(import_module(_WHERE[name]), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
