"""What the API answers: the response models behind the OpenAPI schema."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import BaseModel, Field

from service.labeling.stats import WindowStats, finite_or_none
from service.server.store import Job, StoredWindow
from service.server.tables import JobState

Position = list[float | None]


class ErrorBody(BaseModel):
    message: str = Field(description="One line; for bad input it starts with the field path.",
                         examples=["frames: 120000 frames exceeds the limit of 100000 (limits.max_frames)"])
    detail: list[dict[str, Any]] | None = Field(None, description="Every validation problem, as FastAPI lists them.")


class Certificate(BaseModel):
    """A window's optimality certificate: integral LP optimum, or the gap to the proven bound."""

    integral: bool
    gap: float | None = Field(description="Relative gap (cost - bound) / cost; null if nothing was proven.")
    cost: float | None
    lower_bound: float | None
    status: str
    solve_seconds: float
    total_seconds: float

    @classmethod
    def of(cls, stats: WindowStats | dict) -> Certificate:
        s = stats if isinstance(stats, dict) else stats.to_dict()
        return cls(integral=s["integral"], gap=finite_or_none(s["gap"]), cost=finite_or_none(s["cost"]),
                   lower_bound=finite_or_none(s["lower_bound"]), status=s["status"],
                   solve_seconds=s["solve_seconds"], total_seconds=s["total_seconds"])


class WindowSummary(Certificate):
    index: int
    template: int = Field(description="First frame of the window (labeled by the window before).")
    last: int
    labels: int = Field(0, description="Labels (markers holding a point) in the window's new frames.")
    doubtful: int = Field(0, description="Of those, the ones the result reports doubtful (confidence below its threshold).")

    @classmethod
    def of_stored(cls, window: StoredWindow) -> WindowSummary:
        return cls(index=window.index, template=window.stats["template"], last=window.stats["last"],
                   labels=window.stats.get("labels", 0), doubtful=window.stats.get("doubtful", 0),
                   **Certificate.of(window.stats).model_dump())


class JobSummary(BaseModel):
    id: str
    state: JobState
    source: str = Field(description="'json', or the uploaded file's name.")
    created_at: datetime
    updated_at: datetime
    windows_done: int
    windows_total: int
    error: str | None

    @classmethod
    def of(cls, job: Job) -> JobSummary:
        return cls(id=job.id, state=job.state, source=job.source, created_at=job.created_at, updated_at=job.updated_at,
                   windows_done=job.windows_done, windows_total=job.windows_total, error=job.error)


class JobStatus(JobSummary):
    windows: list[WindowSummary] = Field(description="Every finished window, in order.")
    warnings: list[str] = Field(default_factory=list, description=(
        "Once done, what the labeling warns of, as markerflow track prints it: most labels doubtful, markers "
        "moving further per frame than they are apart, a take not human-sized in its unit, copied columns, "
        "a stretch where no marker is labeled though points are there. An integral window is optimal under "
        "the model, not proven right: these are what the certificate does not see. While queued, why the job "
        "may not start soon (a Dask cluster with no worker)."))


class JobAccepted(JobSummary):
    links: dict[str, str] = Field(description="Status, events and result URLs of the job.")
    warnings: list[str] = Field(default_factory=list, description="What the check of this submission found doubtful "
                                "(a subject model its labeled frame does not fit), and why it may not start soon (a Dask cluster "
                                "with no worker); none for a repeated Idempotency-Key.")


class JobPage(BaseModel):
    jobs: list[JobSummary] = Field(description="Newest first.")
    total: int
    limit: int
    offset: int


class LabeledResult(BaseModel):
    markers: list[str]
    rate: float
    positions: list[list[Position]] = Field(description="[frame][marker] = [x, y, z] mm; null where occluded.")
    occluded: list[list[bool]]
    filled: list[list[Position]] | None = Field(description="Predicted position where occluded, null elsewhere.")
    best_view: list[list[str | None]] | None = Field(
        default=None, description=("[frame][marker] = the camera that shows the marker best (camera mode), null where the "
                                   "marker has no position; null for 3D points."),
    )
    confidence: list[list[float | None]] | None = Field(
        default=None, description=("[frame][marker] = probability that the label is right (calibrated against how often "
                                   "labels are); null where no window said."),
    )


class SolveAnswer(LabeledResult):
    certificate: Certificate


class ParameterInfo(BaseModel):
    name: str
    default: Any
    doc: str


class FormulationInfo(BaseModel):
    name: str
    doc: str
    parameters: list[ParameterInfo]


class Health(BaseModel):
    status: Literal["ok"]
