"""Camera-mode simulator: labeled trajectories -> per-camera 2D detections through a rig."""

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from formulations.cameras.rig import Rig
from service.errors import InputError
from service.io.recording import Recording


@dataclass
class CameraCapture:
    """Per-camera 2D detections and the truth they were made from.

    Index conventions: ``f`` frame, ``c`` camera, ``n`` marker, ``d`` detection.

    Attributes:
        detections: ``detections[f][c]`` is a ``(D, 2)`` array of pixel positions, shuffled.
        detection_markers: ``detection_markers[f][c]`` is ``(D,)`` int: the lowest index of
            the markers behind each detection, -1 for clutter.
        marker_detection: ``(F, C, N)`` int: the detection of ``detections[f][c]`` that
            marker ``n`` produced, -1 if unseen (off-image, behind, occluded, missing). The
            markers behind detection ``d`` are ``flatnonzero(marker_detection[f, c] == d)``;
            more than one means a merged blob.
        truth: The projected 3D trajectories (rig world frame, mm; NaN where missing).
        first_frame: ``truth`` of frame 0, the frame the user labels.
    """

    detections: list[list[np.ndarray]]
    detection_markers: list[list[np.ndarray]]
    marker_detection: np.ndarray
    truth: Recording
    first_frame: Recording


def place_in_volume(
    positions: np.ndarray, rig: Rig, up_axis: int = 2
) -> np.ndarray:
    """Move trajectories into the rig's viewing volume, upright.

    The rig's up ``u`` is minus the mean image-y axis of its cameras in world coordinates
    (image y points down in every camera of a normal rig). The recording's up is its
    coordinate axis ``up_axis``: z for the CMU/HDM05 C3D files (85_02: z spans 11..2123 mm,
    feet at z ~ 0), y for many TRC exports. ``Q`` is the smallest rotation taking that axis
    to ``u``. The target ``p*`` is the least-squares intersection of the optical axes
    (centre ``o_c``, direction ``a_c``)::

        p* = argmin_p sum_c |(I - a_c a_c^T)(p - o_c)|^2,

    and ``X' = Q (X - mean X) + p*``, with the mean over all frames and markers.

    Args:
        positions: ``(F, N, 3)`` millimetres, NaN where missing.
        rig: The cameras.
        up_axis: The recording's vertical coordinate axis, 0, 1 or 2.

    Returns:
        ``(F, N, 3)`` positions in the rig's world frame, mm.

    Raises:
        InputError: No finite position at all (e.g. ``start_frame`` past the end).
    """
    if not np.isfinite(positions).any():  # an empty slice or no sample: nothing to centre
        raise InputError(f"no marker position in the {len(positions)} frames to place; eval needs at least 2 frames")
    R = rig.rotation
    up = -R[:, 1].mean(axis=0)
    up /= np.linalg.norm(up)
    e = np.eye(3)[up_axis]
    # Rodrigues vector of the rotation e -> up: axis e x up, angle atan2(|e x up|, e . up).
    cross = np.cross(e, up)
    sine = np.linalg.norm(cross)
    Q = cv2.Rodrigues(cross * (np.arctan2(sine, e @ up) / max(sine, 1e-12)))[0]
    axes = R[:, 2]
    perp = np.eye(3) - axes[:, :, None] * axes[:, None, :]
    target = np.linalg.solve(perp.sum(axis=0), np.einsum("cij,cj->i", perp, rig.centres))
    return (positions - np.nanmean(positions, axis=(0, 1))) @ Q.T + target


def simulate_cameras(
    truth: Recording,
    rig: Rig,
    pixel_noise: float,
    merge_radius_px: float,
    occlusion_rate: float,
    occlusion_burst_frames: float,
    clutter_per_camera: float,
    seed: int,
) -> CameraCapture:
    """Turn labeled trajectories, already in the rig's world frame, into 2D detections.

    Steps, all from one ``numpy.random.default_rng(seed)``:

    1. Project every sample into every camera (``Rig.project``, i.e. ``cv2.projectPoints``).
    2. Add ``N(0, pixel_noise^2)`` to each pixel coordinate.
    3. Drop projections behind a camera or off the sensor (``[-0.5, w - 0.5]`` per axis), and missing samples.
    4. Occlude in bursts with a visible/occluded Markov chain per (camera, marker):
       ``p_leave = 1/b``, ``p_enter = r / (b (1 - r))`` for stationary rate ``r`` and mean
       burst ``b``. Frame 0 is never occluded: the user labels it.
    5. Merge projections within ``merge_radius_px`` of each other (transitively, per
       frame and camera) into one detection at their mean.
    6. Add ``Poisson(clutter_per_camera)`` clutter per frame and camera, uniform on the image.
    7. Shuffle the detections of each frame and camera.

    Args:
        truth: Labeled trajectories in the rig's world frame (see ``place_in_volume``), mm.
        rig: The cameras.
        pixel_noise: Standard deviation of the detection noise, pixels.
        merge_radius_px: Projections closer than this merge; 0 never merges.
        occlusion_rate: Long-run occluded fraction, in ``[0, 1)``.
        occlusion_burst_frames: Mean occlusion run length, >= 1.
        clutter_per_camera: Poisson mean of spurious detections per frame and camera.
        seed: Seed of the generator; the capture is a function of it.

    Returns:
        The detections with their true markers.

    Raises:
        InputError: Fewer than 2 frames, a setting out of range or a marker missing in frame 0.
    """
    if truth.n_frames < 2:  # as `track`: the labeled frame and at least one to label
        raise InputError(f"the scenario's frames leave {truth.n_frames}; eval needs at least 2 frames")
    r, b = occlusion_rate, occlusion_burst_frames
    if not (0.0 <= r < 1.0 and b >= 1.0 and r / (b * (1.0 - r)) <= 1.0):
        raise InputError(
            f"occlusion rate {r} with mean burst {b} frames is not reachable"
        )
    missing = truth.missing()
    if missing[0].any():
        raise InputError(
            f"marker {truth.names[np.argmax(missing[0])]} is missing in frame 0"
        )
    rng = np.random.default_rng(seed)
    F, N, C = truth.n_frames, truth.n_markers, len(rig)
    positions = np.where(missing[..., None], np.nan, truth.positions)
    samples = np.nan_to_num(positions.reshape(-1, 3))
    pixels = rig.project(samples).reshape(F, N, C, 2).transpose(0, 2, 1, 3)
    pixels = pixels + rng.normal(0.0, pixel_noise, pixels.shape)
    size = rig.image_size[None, :, None, :]
    seen = (
        (rig.depth(samples).reshape(F, N, C).transpose(0, 2, 1) > 0)
        & (pixels >= -0.5).all(axis=3)  # on the sensor, as ``Camera.in_image`` (pixel centres at integers)
        & (pixels <= size - 0.5).all(axis=3)
        & ~missing[:, None, :]
        & ~_occlusions(rng, (F, C, N), r / (b * (1.0 - r)), 1.0 / b)
    )
    f, c, n = np.nonzero(seen)
    blob = _merge(pixels[f, c, n], f * C + c, merge_radius_px)
    n_blobs = blob.max() + 1 if blob.size else 0
    count = np.bincount(blob, minlength=n_blobs)[:, None]
    blob_xy = np.stack(
        [np.bincount(blob, pixels[f, c, n, i], n_blobs) for i in range(2)], 1
    )
    blob_marker = np.full(n_blobs, N, dtype=int)
    np.minimum.at(blob_marker, blob, n)
    blob_group = np.zeros(n_blobs, dtype=int)
    blob_group[blob] = f * C + c
    group, clutter_xy = _clutter(rng, F * C, rig.image_size, clutter_per_camera)
    xy = np.concatenate([blob_xy / np.maximum(count, 1), clutter_xy])
    markers = np.concatenate([blob_marker, np.full(len(group), -1)])
    group = np.concatenate([blob_group, group])
    # Sorting by (group, random key) shuffles within each (frame, camera) in one pass.
    order = np.lexsort((rng.random(len(group)), group))
    starts = np.searchsorted(group[order], np.arange(F * C + 1))
    rank = np.empty(len(order), dtype=int)
    rank[order] = np.arange(len(order)) - starts[group[order]]
    marker_detection = np.full((F, C, N), -1, dtype=int)
    marker_detection[f, c, n] = rank[blob]
    return CameraCapture(
        detections=_per_frame_camera(xy[order], starts, C),
        detection_markers=_per_frame_camera(markers[order], starts, C),
        marker_detection=marker_detection,
        truth=Recording(names=list(truth.names), positions=positions, rate=truth.rate),
        first_frame=Recording(
            names=list(truth.names), positions=positions[:1], rate=truth.rate
        ),
    )


def _per_frame_camera(
    values: np.ndarray, starts: np.ndarray, C: int
) -> list[list[np.ndarray]]:
    """Split group-sorted ``values`` at ``starts`` into ``[frame][camera]`` lists."""
    parts = np.split(values, starts[1:-1])
    return [parts[i : i + C] for i in range(0, len(parts), C)]


def _occlusions(
    rng: np.random.Generator, shape: tuple[int, ...], p_enter: float, p_leave: float
) -> np.ndarray:
    """Bool occlusion mask from the two-state chain along axis 0, visible in frame 0."""
    u = rng.random(shape)
    occluded = np.zeros(shape, dtype=bool)
    for f in range(1, shape[0]):
        occluded[f] = np.where(occluded[f - 1], u[f] >= p_leave, u[f] < p_enter)
    return occluded


def _merge(xy: np.ndarray, group: np.ndarray, radius: float) -> np.ndarray:
    """Blob index ``(P,)`` of each point: connected components of ``|x_i - x_j| < radius``.

    A third coordinate ``group * (2 radius + 1)`` puts points of different (frame, camera)
    groups more than ``radius`` apart, so one k-d tree serves all groups at once.
    """
    if radius <= 0.0 or len(xy) == 0:
        return np.arange(len(xy))
    lifted = np.column_stack([xy, group * (2.0 * radius + 1.0)])
    # query_pairs counts distances <= r; nextafter down makes "closer than" strict.
    pairs = cKDTree(lifted).query_pairs(
        np.nextafter(radius, 0.0), output_type="ndarray"
    )
    graph = coo_matrix(
        (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), (len(xy),) * 2
    )
    return connected_components(graph, directed=False)[1]


def _clutter(
    rng: np.random.Generator, n_groups: int, image_size: np.ndarray, rate: float
) -> tuple[np.ndarray, np.ndarray]:
    """``Poisson(rate)`` uniform points per (frame, camera) group: group ids and pixels."""
    group = np.repeat(np.arange(n_groups), rng.poisson(rate, n_groups))
    n_cameras = len(image_size)
    return group, rng.random((len(group), 2)) * image_size[group % n_cameras] - 0.5  # the sensor, as in_image
