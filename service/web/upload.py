"""The page's upload form as a checked ``Submission``: the same checks as ``POST /v1/jobs``.

A ``.c3d``/``.trc`` file goes through the API's upload path (read in a bounded child
process), with lp-l1 and a window of 20 where the form leaves them blank; a capture
document (``.json``) through the API's JSON path, the form's options put in place of the
document's own only where the user gave them (a blank field keeps the document's).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from starlette.datastructures import FormData, UploadFile

from service.capture.document import CaptureDocument
from service.errors import InputError
from service.server.limits import check_body_limits
from service.server.prescan import check_depth
from service.server.settings import Limits
from service.server.submission import (
    UPLOAD_SUFFIXES,
    Submission,
    document_submission,
    flag_field,
    json_object_field,
    upload_submission,
)

FIELDS = ("file", "formulation", "parameters", "window", "association", "model", "start", "end", "second_pass")
MODEL_OPTION = "model" in CaptureDocument.model_fields  # a subject model in place of the labeled first frame


def form_submission(form: FormData, limits: Limits) -> Submission:
    """The capture the form uploads, with its options.

    Raises:
        InputError: A missing file, a bad option, or anything the API refuses, named by field.
    """
    for name in form:
        if name not in FIELDS:
            raise InputError(f"{name}: unknown form field")
    upload = form.get("file")
    if not isinstance(upload, UploadFile) or not upload.filename:
        raise InputError("file: choose a capture file (.json, .c3d, .trc or .csv)")
    name = Path(upload.filename).name
    chosen, parameters = _text(form, "formulation"), _text(form, "parameters")
    formulation = _formulation(chosen or "lp-l1", parameters)
    window = _text(form, "window")
    model = form.get("model")
    model = model if MODEL_OPTION and isinstance(model, UploadFile) and model.filename else None
    if Path(name).suffix.lower() in UPLOAD_SUFFIXES:
        extra: list[tuple[str, str | UploadFile]] = [("model", model)] if model is not None else []
        extra += [(key, value) for key in ("start", "end", "second_pass") if (value := _text(form, key))]
        fields = FormData([("file", upload), ("formulation", formulation), ("window", window or "20"), *extra])
        return upload_submission(fields, limits)
    if Path(name).suffix.lower() != ".json":
        raise InputError(f"file: {name} is not a capture document (.json) or a labeled .c3d/.trc/.csv file")
    if _text(form, "start") or _text(form, "end"):
        raise InputError("start: a capture document is labeled from its frame 0; start and end are for .c3d/.trc/.csv")
    upload.file.seek(0)
    body = upload.file.read()
    check_body_limits(body, limits)  # nesting and sizes from the bytes, before the parse
    document = _json(body, f"file: {name}")
    if not isinstance(document, dict):
        raise InputError(f"file: {name} is not a capture document (a JSON object)")
    if chosen or parameters:
        document["formulation"] = _documents_formulation(document.get("formulation"), chosen, parameters)
    if window:
        document["window"] = _whole(window)
    if passes := _text(form, "second_pass"):
        document["second_pass"] = flag_field(passes, "second_pass")  # "maybe" was read as false
    association = _text(form, "association")
    if association:
        document["association"] = association
    if model is not None:
        document["model"] = _json_file(model, "model")
    return replace(document_submission(json.dumps(document).encode(), limits), source=name)


def _text(form: FormData, name: str) -> str:
    value = form.get(name)
    if value is not None and not isinstance(value, str):
        raise InputError(f"{name}: expected text, not a file")
    return (value or "").strip()


def _formulation(name: str, parameters: str) -> str:
    """The formulation field as ``upload_submission`` reads it: a name, or a JSON table of the
    name and the parameters object the form's ``parameters`` field gives."""
    if not parameters:
        return name
    return json.dumps({**json_object_field(parameters, "parameters"), "name": name})


def _documents_formulation(own: object, chosen: str, parameters: str) -> str | dict:
    """The formulation of a capture document the form changes: the form's name, else the
    document's (its own table's parameters kept when the name stays), with the form's
    parameters over them. Parameters alone once ran lp-l1 on a document that asked for ilp."""
    table = {"name": own} if isinstance(own, str) else dict(own) if isinstance(own, dict) else {"name": "lp-l1"}
    if chosen and chosen != table.get("name"):
        table = {"name": chosen}
    if not parameters:
        return table
    # the chosen name stays: a "name" among the parameters once ran mht in place of the ilp chosen
    return {**table, **json_object_field(parameters, "parameters"), **({"name": table["name"]} if "name" in table else {})}


def _whole(window: str) -> int:
    try:
        return int(window)
    except ValueError:
        raise InputError(f"window: expected a whole number of frames, got {window!r}") from None


def _json_file(upload: UploadFile, field: str) -> object:
    upload.file.seek(0)
    data = upload.file.read()
    check_depth(data, field)
    return _json(data, field)


def _json(data: bytes, where: str) -> object:
    try:
        return json.loads(data)
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise InputError(f"{where}: not a JSON document ({error})") from None
