"""An uploaded labeled take fitted to a subject model, as ``markerflow model`` fits one.

The take (``.c3d``, ``.trc`` or markerflow ``.csv``) is read in the bounded child process
of ``read_isolated``, exactly as a ``POST /v1/jobs`` upload is. Without a template the
markers are grouped by the variances of their distances (``fit_subject``), which needs a
take with motion; with a marker-set template (a shipped ``markerset`` name, or the
``template`` TOML itself) a labeled static take is enough (``fit_template``). Every
problem is an ``InputError`` whose message starts with the form field.
"""

from __future__ import annotations

import tomllib

import numpy as np
from starlette.datastructures import FormData, UploadFile

from formulations.errors import FormulationError
from formulations.subject.fit import fit_subject
from formulations.subject.model import SubjectModel
from formulations.subject.template import Template, base_name, fit_template
from service.capture.markerset import load_template, shipped
from service.capture.model_input import MIN_SHARED
from service.errors import InputError
from service.server.settings import Limits
from service.server.submission import labeled_upload, read_upload

MODEL_FIELDS = ("file", "markerset", "template")
MODEL_SUFFIXES = (".c3d", ".trc", ".csv")
# Peak memory of fit_subject per frame and marker pair: its distance matrix D is computed over
# (frames, markers, markers, 3) differences at once (measured 57 B on CMU 85_02).
FIT_BYTES_PER_FRAME_PAIR = 64
MAX_TEMPLATE_BYTES = 2**20  # a shipped template is 2-4 KiB; Starlette caps a text field at 1 MiB too


def fit_upload(form: FormData, limits: Limits) -> SubjectModel:
    """The subject model of the form's ``file``, under its ``markerset`` or ``template`` if given.

    Raises:
        InputError: An unknown field, a file that is not a labeled take, a take too short
            or too static to separate segments (the markers and why), a take sharing too few
            names with the template, or a fit over the memory limit.
    """
    upload, filename = labeled_upload(form, MODEL_FIELDS, MODEL_SUFFIXES, "take")
    template = _template(form.get("markerset"), form.get("template"))
    take = read_upload(upload, filename, limits)
    positions = np.where(take.missing()[:, :, None], np.nan, take.positions)
    source = f"file: {filename.name}"
    if not np.isfinite(positions).any():
        raise InputError(f"{source}: no marker has a position in any frame; upload a labeled take")
    try:
        if template is not None:
            _check_shared_names(take.names, template, source)
            return fit_template(template, take.names, positions)
        _check_fit_memory(positions.shape[0], positions.shape[1], limits, source)
        return fit_subject(take.names, positions).model
    except FormulationError as error:
        raise InputError(f"{source}: {error}") from None


def _template(markerset: str | UploadFile | None, template: str | UploadFile | None) -> Template | None:
    """A shipped template by name, or one uploaded as TOML text; never a path on the server."""
    if markerset is not None and template is not None:
        raise InputError("markerset: give a shipped marker set's name or a template, not both")
    if markerset is not None:
        if not isinstance(markerset, str) or markerset not in shipped():
            shown = markerset if isinstance(markerset, str) else "a file"
            raise InputError(f"markerset: unknown marker set {shown!r} (shipped: {', '.join(shipped())}; "
                             "or upload your own TOML as template)")
        return load_template(markerset)
    if template is None:
        return None
    data = template.encode() if isinstance(template, str) else template.file.read(MAX_TEMPLATE_BYTES + 1)
    if len(data) > MAX_TEMPLATE_BYTES:
        raise InputError(f"template: over {MAX_TEMPLATE_BYTES // 2**10} KiB; a marker-set template is a few KiB")
    try:
        table = tomllib.loads(data.decode())
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise InputError(f"template: not valid TOML ({error})") from None
    except RecursionError:
        raise InputError("template: nested too deeply to be a marker-set template") from None
    try:
        return Template.from_dict(table, "template")
    except FormulationError as error:
        raise InputError(str(error)) from None


def _check_shared_names(names: list[str], template: Template, source: str) -> None:
    """As for a model (``check_shared_names``): fewer than half the take's names in the template is another marker set."""
    known = {m for members in template.segments.values() for m in members} | {m for _, c in template.joints for m in c}
    foreign = [name for name in names if base_name(name) not in known]
    shared = len(names) - len(foreign)
    if shared < MIN_SHARED * len(names):
        raise InputError(
            f"{source}: only {shared} of its {len(names)} markers are in marker set {template.name!r} "
            f"(not in it: {', '.join(foreign[:12])}{' ...' if len(foreign) > 12 else ''})"
        )


def _check_fit_memory(frames: int, markers: int, limits: Limits, source: str) -> None:
    """A fit may take the memory a read may (``limits.reader_memory_bytes``); refused before it starts."""
    need = FIT_BYTES_PER_FRAME_PAIR * frames * markers**2
    if need > limits.reader_memory_bytes:
        raise InputError(
            f"{source}: fitting {frames} frames x {markers} markers needs about {need // 2**20} MiB, over the limit "
            f"of {limits.reader_memory_bytes // 2**20} MiB (limits.reader_memory_bytes); upload fewer frames"
        )
