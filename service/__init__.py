"""The application around the mathematics: captures, files, labeling, evaluation, CLI and HTTP service.

    from service import Capture, LabelingOptions, CaptureLabeling, write_labeled

    capture = Capture(names, first_frame, rate=120.0, points=frames)
    labels, windows = CaptureLabeling(capture, LabelingOptions(formulation="lp-l1")).label()
    write_labeled("take_labeled.c3d", labels)
"""

from service.capture.capture import Capture, LabelingOptions
from service.capture.document import CaptureDocument
from service.errors import InputError
from service.io.calibration import load_calibration
from service.io.formats import read_labeled, write_labeled
from service.io.recording import LabeledTrajectories, Recording, UnlabeledCloud
from service.labeling.capture_labeling import CaptureLabeling

__all__ = [
    "Capture", "CaptureDocument", "CaptureLabeling", "InputError", "LabeledTrajectories", "LabelingOptions",
    "Recording", "UnlabeledCloud", "load_calibration", "read_labeled", "write_labeled",
]
