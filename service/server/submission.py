"""A submitted capture, checked whole before it is accepted: a job never fails on bad input.

Two bodies are accepted: a capture document (``application/json``), or a labeled
``.c3d``/``.trc`` upload (``multipart/form-data``) relabeled from its first frame, as
``markerflow track`` does. Both become the same validated ``CaptureDocument``, which is
what the store keeps as the job's input. Every problem is an ``InputError`` whose
message starts with the field path.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, replace
from pathlib import Path

from pydantic import ValidationError
from starlette.datastructures import FormData, UploadFile

from formulations.methods.registry import describe
from service.capture.capture import LabelingOptions
from service.capture.document import CaptureDocument, capture_document_of, describe_validation_error
from service.capture.formulation_spec import formulation_from_table
from service.capture.from_recording import capture_from_span, require_complete_first_frame
from service.capture.span import frame_span
from service.errors import InputError
from service.io.isolated import ReaderBounds, read_isolated
from service.io.recording import Recording
from service.labeling.capture_labeling import CaptureLabeling
from service.labeling.spans import window_spans
from service.labeling.take_warnings import model_misfit_warning
from service.server.limits import check_limits
from service.server.model_submission import document_with_model, model_field
from service.server.prescan import check_depth
from service.server.settings import Limits
from service.server.tables import Upload

UPLOAD_FIELDS = ("file", "formulation", "window", "model", "start", "end", "second_pass")
UPLOAD_SUFFIXES = (".c3d", ".trc", ".csv")  # .csv: a table markerflow wrote


@dataclass(frozen=True)
class Submission:
    """A checked capture: the document, where it came from, its window count, and the warnings
    its check raised (a subject model the labeled frame does not fit)."""

    document: CaptureDocument
    source: str
    n_windows: int
    warnings: tuple[str, ...] = ()
    upload: Upload | None = None  # the file it was read from: its result is written as the CLI writes it

    def stored(self) -> bytes:
        return self.document.model_dump_json().encode()


def document_submission(body: bytes, limits: Limits) -> Submission:
    """A JSON capture document, parsed and checked."""
    return _checked(capture_document_of(body), "json", limits)


def labeled_upload(form: FormData, fields: tuple[str, ...], suffixes: tuple[str, ...], what: str) -> tuple[UploadFile, Path]:
    """The form's ``file`` upload and its name, after checking the form has only ``fields``
    and the file one of ``suffixes`` (one-line errors naming what is wrong)."""
    for name in form:
        if name not in fields:
            raise InputError(f"{name}: unknown form field; the fields are {', '.join(fields)}")
        if len(form.getlist(name)) > 1:  # which one was meant? the last silently won
            raise InputError(f"{name}: given {len(form.getlist(name))} times; send each field once")
    listed = ", ".join(suffixes[:-1]) + f" or {suffixes[-1]}"
    upload = form.get("file")
    if not isinstance(upload, UploadFile):
        raise InputError(f"file: upload a labeled {listed} {what} in the form field 'file'")
    filename = Path(upload.filename or "")
    if filename.suffix.lower() not in suffixes:
        raise InputError(f"file: {filename.name or 'the upload'} is not a {listed} file")
    return upload, filename


def upload_submission(form: FormData, limits: Limits) -> Submission:
    """A ``.c3d``/``.trc`` upload with optional ``formulation`` (name or JSON object), ``window``,
    ``second_pass`` (true or false),
    ``start`` and ``end`` (relabel frames start .. end - 1 from the file's labels at ``start``,
    the markers absent there left out, as ``markerflow track --start`` does) or ``model`` (a
    subject model JSON: frame 0 may then be partly labeled, ``model_submission``)."""
    upload, filename = labeled_upload(form, UPLOAD_FIELDS, UPLOAD_SUFFIXES, "file")
    options = LabelingOptions(formulation=_formulation_field(form.get("formulation")), window=_window_field(form.get("window")),
                              second_pass=flag_field(form.get("second_pass"), "second_pass"))
    model = model_field(form.get("model"))
    start, end = _frame_field(form.get("start"), "start"), _frame_field(form.get("end"), "end")
    recording = read_upload(upload, filename, limits)
    upload.file.seek(0)
    data = upload.file.read()
    if start is None and model is None:  # frame 0 is the labeled frame: every marker must be there
        require_complete_first_frame(recording, "file", "start=", "; or send a subject model as 'model'")
    try:
        if model is not None:  # frames start .. end - 1, their first's labels kept (track --model --keep-labels)
            document = document_with_model(_span(recording, start or 0, end), model, options, filename.name)
            return replace(_checked(document, filename.name, limits), upload=Upload(filename.suffix.lower(), data,
                                                                                    start or 0))
        capture, absent = capture_from_span(recording, start or 0, end)
        document = CaptureDocument.of(capture, options)
    except ValidationError as error:
        raise InputError(describe_validation_error(error)) from None
    except InputError as error:  # worded for the command line: here the fields are start= and end=
        raise InputError(str(error).replace("--start ", "start=").replace("--end ", "end=")) from None
    kept = Upload(filename.suffix.lower(), data, start or 0, tuple(absent))
    return replace(_checked(document, filename.name, limits), upload=kept)


def _span(recording: Recording, start: int, end: int | None) -> Recording:
    """Frames ``start .. end - 1`` of ``recording`` (``frame_span`` checks them)."""
    stop = frame_span(start, end, recording.n_frames)
    return replace(recording, positions=recording.positions[start:stop])


def _frame_field(value: str | UploadFile | None, field: str) -> int | None:
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    if not isinstance(value, str) or not re.fullmatch(r"\s*[0-9]{1,9}\s*", value):
        raise InputError(f"{field}: expected a frame number from 0, got {value!r}")
    return int(value)


def _checked(document: CaptureDocument, source: str, limits: Limits) -> Submission:
    check_limits(document, limits)
    check_formulation(document.formulation)
    return Submission(document, source, len(window_spans(document.n_frames, document.window)),
                      labeling_warnings(document))


def labeling_warnings(document: CaptureDocument) -> tuple[str, ...]:
    """What the library finds doubtful in a document (a subject model its labeled frame does
    not fit), after checking its options (formulation, window, association) itself: on the
    first two frames, which costs nothing in either input mode."""
    # A validated document has either points or detections.
    head = {"points": document.points[:2]} if document.points is not None else {
        "detections": {camera: frames[:2] for camera, frames in (document.detections or {}).items()}}
    labeling = CaptureLabeling(document.model_copy(update=head).capture(), document.options())
    warning = model_misfit_warning(labeling.model_misfits, 0)
    return (warning,) if warning else ()


def check_formulation(formulation: str | dict) -> None:
    """The formulation exists and every parameter has its default's type (a bool is a bool).

    The formulations check numbers' ranges themselves; flags and names are checked here
    so that ``decompose = "no"`` is refused rather than read as true.
    """
    table = {"name": formulation} if isinstance(formulation, str) else formulation
    # Types first, so the message names the field path (formulation.decompose) as others do.
    defaults = {p.name: p.default for d in describe() if d.name == table.get("name") for p in d.parameters}
    for name, value in table.items():
        default = defaults.get(name)
        if isinstance(default, (bool, str)) and type(value) is not type(default):
            raise InputError(f"formulation.{name}: expected a {type(default).__name__}, got {value!r}")
    formulation_from_table(table, "formulation")


def _formulation_field(value: str | UploadFile | None) -> str | dict:
    if value is None:
        return "lp-l1"
    if not isinstance(value, str):
        raise InputError("formulation: give a name or a JSON object, not a file")
    if not value.lstrip().startswith("{"):
        return value
    return json_object_field(value, "formulation")


def json_object_field(value: str, field: str) -> dict:
    """A form field holding a JSON object, nesting checked before the parser sees it."""
    check_depth(value.encode(), field)  # deep nesting would overflow the parser
    try:
        table = json.loads(value)
    except json.JSONDecodeError as error:
        raise InputError(f"{field}: not a JSON object ({error})") from None
    if not isinstance(table, dict):
        raise InputError(f'{field}: not a JSON object, e.g. {{"time_limit": 10}}')
    return table


def flag_field(value: str | UploadFile | None, field: str) -> bool:
    """``true`` or ``false`` (as a capture document's JSON says them); absent: true."""
    if value is None:
        return True
    if not isinstance(value, str) or value.strip().lower() not in ("true", "false"):
        raise InputError(f"{field}: expected true or false, got {value!r}")
    return value.strip().lower() == "true"


def _window_field(value: str | UploadFile | None) -> int:
    if value is None:
        return LabelingOptions().window
    # ASCII digits only: str.isdigit() takes '²', which int() refuses; 9 digits keep int() cheap.
    if not isinstance(value, str) or not re.fullmatch(r"\s*-?[0-9]{1,9}\s*", value):
        raise InputError(f"window: expected a whole number of frames, got {value!r}")
    return int(value)


def read_upload(upload: UploadFile, filename: Path, limits: Limits) -> Recording:
    """The upload read in a bounded child process (``read_isolated``), never in the server."""
    bounds = ReaderBounds(limits.reader_memory_bytes, limits.reader_seconds, limits.max_markers, limits.max_frames)
    upload.file.seek(0)
    try:
        return read_isolated(upload.file.read(), filename.suffix.lower(), bounds)
    except InputError as error:
        raise InputError(f"file: {filename.name}: {error}") from None
