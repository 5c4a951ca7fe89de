"""Save and load a WindowProblem as one compressed ``.npz`` file (for fixtures and bug reports)."""

from __future__ import annotations

import zipfile
import zlib
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from formulations.window.problem import WindowProblem
from service.errors import InputError

_ARRAYS = ("node_kind", "node_object", "node_frame", "node_location", "arc_tail", "arc_head",
           "arc_cost", "layout_pairs", "layout_weight")


def save_window(path: str | Path, problem: WindowProblem) -> None:
    """Write ``problem`` to ``path`` (numpy's .npz; the resource matrix as its CSR parts)."""
    resources = problem.resources.tocsr()
    np.savez_compressed(
        path, n_objects=problem.n_objects, n_frames=problem.n_frames,
        resource_data=resources.data, resource_indices=resources.indices,
        resource_indptr=resources.indptr, resource_shape=np.array(resources.shape),
        **{name: getattr(problem, name) for name in _ARRAYS},
    )


def load_window(path: str | Path) -> WindowProblem:
    """Read a window written by ``save_window``.

    An empty, truncated or damaged file is a user's file, not a bug: numpy lets zipfile's
    and zlib's errors through, and its EOFError on an empty file reached the CLI's handler
    for end of input at a prompt, which printed a bare "aborted".

    Raises:
        InputError: ``<path>: not a markerflow window file (...)``, one line.
    """
    try:
        with np.load(path) as data:
            resources = sp.csr_matrix(
                (data["resource_data"], data["resource_indices"], data["resource_indptr"]),
                shape=tuple(data["resource_shape"]),
            )
            return WindowProblem(
                n_objects=int(data["n_objects"]), n_frames=int(data["n_frames"]), resources=resources,
                **{name: data[name] for name in _ARRAYS},
            )
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile, zlib.error, NotImplementedError) as error:
        # NotImplementedError: zipfile on a compression method or zip version it cannot read
        raise InputError(f"{path}: not a markerflow window file ({error or 'the file ends early'})") from None
