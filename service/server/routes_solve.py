"""``POST /v1/solve``: one window labeled while the caller waits, with its certificate."""

from __future__ import annotations

from fastapi import APIRouter, Depends, Request
from starlette.concurrency import run_in_threadpool

from service.errors import InputError
from service.labeling.capture_labeling import CaptureLabeling
from service.server.auth import caller
from service.server.bodies import read_submission, request_body
from service.server.results import trajectories_json
from service.server.schemas import Certificate, ErrorBody, SolveAnswer
from service.server.settings import Limits
from service.server.submission import Submission

router = APIRouter(prefix="/v1", tags=["solve"])


@router.post(
    "/solve", response_model=SolveAnswer, dependencies=[Depends(caller)],
    openapi_extra=request_body("A capture of at most one window (frames <= window, <= limits.max_solve_frames).",
                               upload=False),
    responses={401: {"model": ErrorBody}, 413: {"model": ErrorBody}, 415: {"model": ErrorBody},
               422: {"model": ErrorBody}},
)
async def solve(request: Request) -> SolveAnswer:
    """Label a one-window capture synchronously; answer the labels and the window's certificate."""
    limits: Limits = request.app.state.settings.limits
    submission = await read_submission(request, limits, upload=False)
    return await run_in_threadpool(_solve, submission, limits)


def _solve(submission: Submission, limits: Limits) -> SolveAnswer:
    document = submission.document
    frames = document.n_frames
    if frames > limits.max_solve_frames:
        raise InputError(f"frames: {frames} frames exceeds the limit of {limits.max_solve_frames} (limits.max_solve_frames)")
    if frames > document.window:
        raise InputError(f"frames: {frames} frames is more than one window (window = {document.window}); "
                         "submit it as a job (POST /v1/jobs)")
    result, windows = CaptureLabeling(document.capture(), document.options()).label()
    return SolveAnswer(**trajectories_json(result), certificate=Certificate.of(windows[0]))
