"""The request bodies of ``POST /v1/jobs`` and ``POST /v1/solve``: read by hand, described by hand.

The jobs route takes JSON *or* a multipart upload, which FastAPI's body parameters cannot
express, so both routes read the raw body (after the body-size limit) and declare it in
OpenAPI here; the JSON schema is ``CaptureDocument``'s own.
"""

from __future__ import annotations

from fastapi import HTTPException, Request
from starlette.concurrency import run_in_threadpool

from service.server.limits import check_body_limits
from service.server.settings import Limits
from service.server.submission import UPLOAD_FIELDS, Submission, document_submission, upload_submission

CAPTURE_REF = {"$ref": "#/components/schemas/CaptureDocument"}

EXAMPLE_DOCUMENT = {
    "units": "mm", "rate": 100, "markers": ["A", "B", "C"],
    "first_frame": [[0, 0, 1000], [100, 0, 1000], [0, 100, 1000]],
    "points": [
        [[0, 0, 1000], [100, 0, 1000], [0, 100, 1000]],
        [[101, 1, 1000], [1, 101, 1000], [1, 1, 1000]],
        [[2, 2, 1000], [102, 2, 1000], [2, 102, 1000]],
    ],
    "formulation": "lp-l1", "window": 20,
}

UPLOAD_SCHEMA = {
    "type": "object",
    "required": ["file"],
    "properties": {
        "file": {"type": "string", "format": "binary",
                 "description": "Labeled .c3d, .trc or markerflow .csv; frame 0 (or 'start') names the markers."},
        "formulation": {"type": "string", "description": "A name, or a JSON object {\"name\": ..., parameters}.",
                        "default": "lp-l1"},
        "window": {"type": "integer", "minimum": 2, "default": 20},
        "model": {"type": "string", "format": "binary", "description": "Subject model JSON (markerflow model): "
                  "frame 0's labels are kept and the model names the markers they leave out."},
        "start": {"type": "integer", "minimum": 0, "description": "Relabel from the file's labels at this frame "
                  "(default 0, which must then have every marker); markers absent there are written missing. "
                  "Not with a model."},
        "end": {"type": "integer", "minimum": 2, "description": "Label frames before this one (default: to the last)."},
    },
}


def request_body(description: str, upload: bool) -> dict:
    content = {"application/json": {"schema": CAPTURE_REF, "examples": {"three markers": {"value": EXAMPLE_DOCUMENT}}}}
    if upload:
        content["multipart/form-data"] = {"schema": UPLOAD_SCHEMA}
    return {"requestBody": {"required": True, "description": description, "content": content}}


async def read_submission(request: Request, limits: Limits, upload: bool) -> Submission:
    """The checked capture of a JSON body, or (``upload``) of a multipart file upload.

    Raises:
        HTTPException: 415 for another media type.
        InputError: Anything wrong with the capture, named by field; a JSON body over a
            limit is refused from its bytes, before it is parsed.
    """
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media == "application/json":
        return await run_in_threadpool(_document, await request.body(), limits)
    if upload and media == "multipart/form-data":
        async with request.form(max_files=2, max_fields=len(UPLOAD_FIELDS)) as form:
            return await run_in_threadpool(upload_submission, form, limits)
    accepted = "application/json or multipart/form-data" if upload else "application/json"
    raise HTTPException(415, f"content-type: send {accepted}, not {media or 'nothing'}")


def _document(body: bytes, limits: Limits) -> Submission:
    check_body_limits(body, limits)  # from the bytes, before the parse builds the document
    return document_submission(body, limits)
