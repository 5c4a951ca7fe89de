"""Candidates for ``per-camera`` association: each marker tracked in each camera's image.

The window holds one object per (camera c, marker n), object o = c N + n. Its candidates in
frame m are the detections of camera c within the gate of the marker's projected guide
prediction; a candidate consumes its detection, so markers gating the same detection of
one camera conflict ("same detection"), and cameras never conflict with each other.

Locations are image-plane positions in mm at the marker's template depth (see
``per_camera_guide``): r = z_nc (x, y) for normalised coordinates (x, y) and z_nc the depth
in camera c of marker n at the template, one scale per object for the whole window, so
arc displacements are mm of sideways motion and the 3D labeler's weights apply. The
template term prefers detections near the prediction p_n(m), in units of its uncertainty
sigma(k) = sigma_0 + k sigma_1 after k frames unseen (as in ``cloud_candidates``):

    g(s_o, v) = w_p min(z_nc ||x_v - x(p_n(m))|| / sigma(k), cap).

The expected displacement into frame m is the image motion of the guide,
z_nc (x(p_n(m)) - x(q_n(m-1))) with q_n(m-1) the guide's position before frame m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from formulations.cameras.per_camera.gating import PerCameraGating
from formulations.cameras.per_camera.guide import PerCameraGuide
from formulations.cameras.per_camera.locate import FrameViews
from formulations.cameras.rig import Rig
from formulations.markers.state import MarkerState
from formulations.window.build import taken_candidates
from formulations.window.candidates import WindowCandidates


@dataclass(frozen=True)
class PerCameraWindow:
    """Candidates of one window and what maps them back to the detections.

    Attributes:
        candidates: Objects o = c N + n.
        camera: ``(K,)`` camera of each candidate.
        detection: ``(K,)`` index of the candidate's detection in its frame and camera.
        n_cameras: C.
    """

    candidates: WindowCandidates
    camera: np.ndarray
    detection: np.ndarray
    n_cameras: int

    def views(self, node_candidate: np.ndarray, path: np.ndarray) -> np.ndarray:
        """``(M, N, C)`` detection each marker took in each camera and frame, -1 for none.

        Args:
            node_candidate: Candidate of each node (``build_window``), -1 for the others.
            path: ``(N C, M)`` node per object and frame (``WindowSolution.path``).
        """
        taken = taken_candidates(node_candidate, path, self.detection)
        return taken.reshape(self.n_cameras, -1, path.shape[1]).transpose(2, 1, 0)


def per_camera_candidates(
    state: MarkerState, rig: Rig, guide: PerCameraGuide, frames: list[FrameViews],
    gating: PerCameraGating = PerCameraGating(),
) -> PerCameraWindow:
    """Gate every camera's detections around the projected guide predictions.

    Args:
        state: The markers at the template frame.
        rig: The C cameras.
        guide: The window's guide track.
        frames: Detections of window frames 1..M.
        gating: Gates and template-term weights.
    """
    n, c_count, m_count = len(state.position), len(rig), len(frames)
    template, depth = rig.image_plane(state.position)  # (C, N, 2), (C, N)
    scale = np.where(depth > 0, depth, np.nan)  # z_nc
    predicted = rig.image_plane(guide.predicted)[0]  # (C, M, N, 2)
    occlusion = predicted * scale[:, None, :, None]
    motion = (predicted - rig.image_plane(guide.previous)[0]) * scale[:, None, :, None]
    motion[:, ~guide.motion_known] = np.nan
    counts = np.array([[len(d) for d in frame.normalised] for frame in frames]).ravel()
    first_column = np.concatenate([[0], np.cumsum(counts)])[:-1].reshape(m_count, c_count)
    sigma = gating.prediction_sigma_mm + gating.prediction_sigma_growth_mm * guide.unseen  # (M, N)
    parts: list[tuple[np.ndarray, ...]] = []
    for m, frame in enumerate(frames):
        for c, found in enumerate(frame.normalised):
            if len(found) == 0:
                continue
            distance = cdist(predicted[c, m], found) * scale[c, :, None]
            marker, detection = np.nonzero(distance <= guide.radius[m][:, None])
            cost = gating.prediction_weight * np.minimum(
                distance[marker, detection] / sigma[m, marker], gating.prediction_cap_sigmas
            )
            parts.append((
                c * n + marker, np.full(len(marker), m + 1), np.full(len(marker), c), detection,
                found[detection] * scale[c, marker, None], cost, first_column[m, c] + detection,
            ))
    obj, frame_of, camera_of, detection, location, cost, column = _stack(parts)
    candidates = WindowCandidates(
        template_location=np.nan_to_num((template * scale[..., None]).reshape(c_count * n, 2)),
        template_occluded=np.tile(~state.visible, c_count), n_frames=m_count,
        object=obj, frame=frame_of, location=location, template_cost=cost,
        resources=sp.csr_matrix((np.ones(len(column)), (np.arange(len(column)), column)), shape=(len(column), counts.sum())),
        occlusion_location=np.nan_to_num(occlusion.transpose(0, 2, 1, 3).reshape(c_count * n, m_count, 2)),
        motion=motion.transpose(0, 2, 1, 3).reshape(c_count * n, m_count, 2),
    )
    return PerCameraWindow(candidates=candidates, camera=camera_of, detection=detection, n_cameras=c_count)


def _stack(parts: list[tuple[np.ndarray, ...]]) -> tuple[np.ndarray, ...]:
    """Concatenate the per-(frame, camera) candidate arrays field by field."""
    if not parts:
        empty = np.zeros(0, dtype=int)
        return empty, empty, empty, empty, np.zeros((0, 2)), np.zeros(0), empty
    return tuple(np.concatenate(field_parts) for field_parts in zip(*parts))
