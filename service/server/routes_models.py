"""``POST /v1/models``: a subject model fitted to an uploaded labeled take, while the caller waits.

Models are not stored: the answer is the versioned JSON ``markerflow model --out`` writes,
which a capture document (``POST /v1/jobs``) takes as ``"model"`` in place of a labeled
first frame. The fit takes seconds of NumPy, so it runs in a worker thread, as
``/v1/solve``'s labeling does, never on the event loop; the job executor is for durable
jobs (stored, resumed, cancelled), which a stateless fit is not. At most
``max_parallel_jobs`` fits run at once (``app.state.model_fits``), each bounded in memory
beforehand (``model_upload``).
"""

from __future__ import annotations

from anyio import to_thread
from fastapi import APIRouter, Depends, HTTPException, Request, Response

from service.capture.markerset import shipped
from service.server.auth import caller
from service.server.model_upload import MODEL_FIELDS, fit_upload
from service.server.schemas import ErrorBody

router = APIRouter(prefix="/v1", tags=["models"])

UPLOAD_SCHEMA = {
    "type": "object",
    "required": ["file"],
    "properties": {
        "file": {"type": "string", "format": "binary",
                 "description": "A labeled .c3d, .trc or markerflow .csv take of the subject: with motion "
                                "(range of motion) to fit segments and joints, or static with a template."},
        "markerset": {"type": "string", "enum": shipped(), "description": "A shipped marker-set template."},
        "template": {"type": "string", "description": "A marker-set template as TOML (configs/markersets/README.md)."},
    },
}
MODEL_SCHEMA = {"type": "object", "description": "The subject model: version, segments, joints, limbs, singles, "
                                                 "marker_radius (as `markerflow model --out` writes)."}


@router.post(
    "/models", dependencies=[Depends(caller)],
    openapi_extra={"requestBody": {"required": True, "content": {"multipart/form-data": {"schema": UPLOAD_SCHEMA}}}},
    responses={200: {"content": {"application/json": {"schema": MODEL_SCHEMA}}, "description": "The subject model."},
               401: {"model": ErrorBody}, 413: {"model": ErrorBody}, 415: {"model": ErrorBody},
               422: {"model": ErrorBody}},
)
async def fit_model(request: Request) -> Response:
    """Fit a subject model (segments, joints, limb lengths) to an uploaded labeled take and answer its JSON."""
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media != "multipart/form-data":
        raise HTTPException(415, f"content-type: send multipart/form-data, not {media or 'nothing'}")
    limits = request.app.state.settings.limits
    async with request.form(max_files=2, max_fields=len(MODEL_FIELDS)) as form:
        model = await to_thread.run_sync(fit_upload, form, limits, limiter=request.app.state.model_fits)
    return Response(model.to_json(), media_type="application/json")
