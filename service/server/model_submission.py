"""A labeled ``.c3d``/``.trc`` upload sent with a subject model: its frame 0 labels kept, the model
names the rest, as ``markerflow track --model M --keep-labels`` does.

The upload's ``model`` field is the model JSON, as a file part or a text field. The markers
frame 0 labels start from their labels (a partly labeled frame is fine; one the model lacks
becomes its single, ``labeled_singles``); the model names the markers absent there. A
file frame 0 labels nothing of is identified from the model alone. A file sharing fewer than
half its marker names with the model is refused (another marker set).
"""

from __future__ import annotations

import json

from pydantic import ValidationError
from starlette.datastructures import UploadFile

from service.capture.capture import LabelingOptions
from service.capture.document import CaptureDocument, describe_validation_error
from service.capture.from_recording import capture_from_recording
from service.capture.model_input import check_shared_names, parse_model
from service.errors import InputError
from service.io.recording import Recording
from service.server.prescan import check_depth


def model_field(value: str | UploadFile | None) -> dict | None:
    """The form's ``model`` (a file part or a text field) as a JSON object, None when not given."""
    if value is None:
        return None
    if isinstance(value, UploadFile):
        value.file.seek(0)
        data = value.file.read()
    else:
        data = value.encode()
    check_depth(data, "model")  # deep nesting would overflow the parser
    try:
        model = json.loads(data)
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise InputError(f"model: not a JSON document ({error})") from None
    if not isinstance(model, dict):
        raise InputError("model: a subject model is a JSON object (what markerflow model writes)")
    return model


def document_with_model(recording: Recording, model: dict, options: LabelingOptions, source: str) -> CaptureDocument:
    """The upload as a capture document labeled from ``model`` and the labels of its frame 0."""
    subject = parse_model(json.dumps(model), "model")
    check_shared_names(recording.names, subject, f"file: {source}")
    absent = recording.without_unlabeled().missing()[0]  # over the markers, as capture.names (*N: points only)
    capture = capture_from_recording(recording)  # points shuffled; frame 0's labels
    labeled = [i for i, name in enumerate(capture.names) if not absent[i]]  # the model's singles if it lacks them
    points = capture.points or []
    fields: dict = {"rate": capture.rate, "points": [frame.tolist() for frame in points], "model": model,
                    "formulation": options.formulation, "window": options.window,
                    # the file's markers frame 0 does not label keep their points, unnamed until the model names them
                    "unnamed_markers": len(capture.names) - len(labeled)}
    if labeled:
        fields.update(markers=[capture.names[i] for i in labeled], first_frame=capture.first_frame[labeled].tolist())
    try:
        return CaptureDocument.model_validate(fields)
    except ValidationError as error:
        raise InputError(describe_validation_error(error)) from None
