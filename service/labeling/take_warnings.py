"""Markers that move more per frame than their neighbours are apart: a warning for the take
(and ``scale_warning``: a take that is not human-sized in its declared unit).

A marker's gate is centred on its prediction. With little motion seen, or motion that
turns within a frame, the prediction is close to the last position, and a marker whose
step s is more than half the distance d to its nearest neighbour then lies nearer that
neighbour's last position than its own: tight rigid clusters on fast segments (a
wheelchair racer's 3-marker clusters 30 mm apart moving 28 mm a frame) swap labels no
matter how the window is solved. The take is read from its labeled result:

    s_n = median over frames of ||x_n(f+1) - x_n(f)||   (both frames labeled)
    d_n = median over frames of min_{j != n} ||x_n(f) - x_j(f)||   (both labeled)

and a marker is flagged when s_n > FAST_RATIO * d_n. A marker on the same position as
another (a copied column, ``coincident``) is not its neighbour.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from formulations.subject.contradiction import SegmentMisfit
from service.errors import InputError
from service.io.recording import Recording
from service.labeling.coincident import COINCIDENT_MM, sampled_rows

FAST_RATIO = 0.5  # s > d / 2: the last position is nearer the neighbour's than the marker's own
LISTED = 4  # markers named in the warning line


@dataclass(frozen=True)
class FastMarker:
    """A marker whose median step per frame exceeds ``FAST_RATIO`` of its neighbour distance (mm)."""

    marker: str
    step_mm: float
    neighbour_mm: float
    neighbour: str


def fast_markers(names: list[str], positions: np.ndarray) -> list[FastMarker]:
    """The flagged markers of labeled ``positions`` ``(F, N, 3)`` (mm, NaN unlabeled), fastest relative first."""
    if len(positions) < 2 or len(names) < 2:
        return []
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=2)  # (F-1, N), NaN unless both labeled
    step = _median_or_nan(steps)
    closest, distance = _nearest(positions)  # (S, N) each
    distance[~np.isfinite(distance)] = np.nan
    spacing = _median_or_nan(distance)
    flagged = np.flatnonzero(step > FAST_RATIO * spacing)  # NaN compares False: unknowns are not flagged
    found = [
        FastMarker(names[n], float(step[n]), float(spacing[n]), names[_most_common(closest[np.isfinite(distance[:, n]), n])])
        for n in flagged
    ]
    return sorted(found, key=lambda f: f.neighbour_mm / f.step_mm)


def _nearest(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(S, N)`` each marker's nearest other marker and its distance on the sampled frames
    (``sampled_rows``; inf where none is labeled with it); a copied column is no neighbour."""
    closest, distance = [], []
    for n, apart in enumerate(sampled_rows(positions)):
        apart[:, n] = np.nan
        apart[apart < COINCIDENT_MM] = np.nan  # (``coincident``)
        nearest = np.where(np.isfinite(apart), apart, np.inf)
        closest.append(np.argmin(nearest, axis=1))
        distance.append(np.min(nearest, axis=1))
    return np.stack(closest, axis=1), np.stack(distance, axis=1)


def fast_motion_warning(fast: list[FastMarker]) -> str | None:
    """One line naming the flagged markers (the first ``LISTED``), or None."""
    if not fast:
        return None
    named = ", ".join(
        f"{f.marker} {f.step_mm:.0f} mm/frame, {f.neighbour_mm:.0f} mm from {f.neighbour}" for f in fast[:LISTED]
    )
    more = f" and {len(fast) - LISTED} more" if len(fast) > LISTED else ""
    plural = (f"{len(fast)} markers move", "their", "their labels")
    subject, its, labels = ("1 marker moves", "its", "its label") if len(fast) == 1 else plural
    return (f"warning: {subject} more per frame than half the distance to {its} nearest "
            f"neighbour (medians: {named}{more}); {labels} may swap at this frame rate")


# Human-scale mocap, generously: skin markers sit 35-190 mm from their nearest neighbour in
# every take we hold (CMU, HDM05, OpenSim, BTS, Vicon, Qualisys, Pose2Sim) and a body moves
# at most a few m/s. A file in the wrong unit is off by 10x-1000x and lands far outside.
SPACING_MM = (1.0, 5000.0)  # median nearest-neighbour distance in the labeled frame
REFUSED_FAR_MARKERS = 4  # two or three objects metres apart may be real; half of four or more cannot all be
# A body in cm read as mm is 10x small (CMU 85_02's 41 markers within 160 mm, 11 mm apart),
# and so are hand and face sets in mm: only the names tell them apart. Five markers named for
# body landmarks (knee, ankle, heel, ASIS, C7, ...) within 400 mm are a body in another unit.
# A landmark token starts the name or follows a side letter or a separator ("LHEE", "R.Heel",
# "Male:C7"), not another letter: "Cheek" is a face marker.
BODY_LANDMARKS = re.compile(r"(?<![A-KM-QS-Za-km-qs-z])(?:ASI|PSI|KNE|ANK|HEE|TOE|C7|CLAV|STRN|SHO|ELB|WR[AB]|THI|TIB|HIP|"
                            r"SACR|ACR)", re.IGNORECASE)
SMALL_BODY = (5, 400.0)  # landmark markers at least, extent under (mm)
MAX_SPEED_MM_S = 50_000.0  # median marker speed: a thrown ball's, not a limb's


def scale_warning(first_frame: np.ndarray, positions: np.ndarray, rate: float, unit: str,
                  spacing: bool = True, names: list[str] | None = None) -> str | None:
    """One line when the take does not look human-sized in ``unit``: the median spacing of
    the labeled ``first_frame`` ``(N, 3)`` (with ``spacing``) or the median speed of the
    labeled ``positions`` ``(F, N, 3)`` (mm, NaN unlabeled) outside
    ``SPACING_MM``/``MAX_SPEED_MM_S``; else None. The spacing can be judged before labeling
    (``track`` does, with ``positions`` its first frame alone): a take in metres read as mm
    puts every point in every gate, and labels for minutes before a later line would say why.

    A warning, not an error: a surveyed site or a mm-sized model is possible, but a wrong
    unit otherwise labels without complaint (gates sized for mm miss points 1000x apart).
    ``names`` (of ``first_frame``'s rows) also judge a body too small (``SMALL_BODY``).
    """
    found: list[str] = []
    apart = marker_spacing_mm(first_frame) if spacing else None
    if apart is not None and not SPACING_MM[0] <= apart <= SPACING_MM[1]:
        found.append(f"markers {apart:.3g} mm from their nearest neighbour in the labeled frame "
                     f"(expected {SPACING_MM[0]:g} mm to {SPACING_MM[1] / 1000:g} m)")
    small = _small_body(first_frame, names) if spacing and names is not None else None
    if small:
        found.append(small)
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=2) if len(positions) > 1 else np.zeros(0)
    steps = steps[np.isfinite(steps)]
    speed = float(np.median(steps)) * rate if len(steps) else 0.0
    if speed > MAX_SPEED_MM_S:
        found.append(f"a median speed of {speed / 1000:.3g} m/s at {rate:g} Hz (expected under {MAX_SPEED_MM_S / 1000:g} m/s)")
    if not found:
        return None
    rate_too = " and frame rate" if speed > MAX_SPEED_MM_S else ""
    return (f"warning: read in {unit}, the take does not look human-sized: {'; '.join(found)}; "
            f"check the file's length unit{rate_too}")


def _small_body(frame: np.ndarray, names: list[str]) -> str | None:
    """``SMALL_BODY``'s finding: markers named for body landmarks within a small volume."""
    landmarks = [n for n, row in zip(names, frame) if BODY_LANDMARKS.search(n) and np.isfinite(row).all()]
    least, extent_under = SMALL_BODY
    seen = frame[np.isfinite(frame).all(axis=1)]
    if len(landmarks) < least:
        return None
    extent = float((seen.max(axis=0) - seen.min(axis=0)).max())
    if extent >= extent_under:
        return None
    return (f"{len(seen)} markers, {', '.join(landmarks[:4])} among them, within {extent:.0f} mm "
            "(a body in cm read as mm?)")


def marker_spacing_mm(frame: np.ndarray) -> float | None:
    """Median distance from each position of ``frame`` ``(N, 3)`` (NaN rows skipped) to its
    nearest other; None with fewer than two."""
    seen = frame[np.isfinite(frame).all(axis=1)]
    return float(np.median(cKDTree(seen).query(seen, k=2)[0][:, 1])) if len(seen) >= 2 else None


def spacing_frame(first_frame: np.ndarray, points: list[np.ndarray] | None) -> np.ndarray:
    """``(N, 3)`` the frame a take's marker spacing is judged on before labeling: the labeled
    first frame, or frame 0's points where fewer than two markers are labeled (a subject model
    is to name them)."""
    first = np.asarray(first_frame, dtype=float).reshape(-1, 3)
    return first if np.isfinite(first).all(axis=1).sum() >= 2 or not points else points[0]


def refuse_wrong_scale(frame: np.ndarray) -> None:
    """Refuse a take whose markers sit under ``SPACING_MM[0]`` apart: optical markers are
    millimetres wide, so that is a wrong unit (metres read as mm), and labeling it puts
    every point in every gate (20 frames of a walk ran for over ten minutes). Likewise over
    ``SPACING_MM[1]`` apart, with ``REFUSED_FAR_MARKERS`` markers or more (markers on a subject
    are centimetres apart: millimetres read as metres): every step is then a thousand times
    the gates, and CMU 85_02 so scaled came back 100 % occluded, written without an error.

    Raises:
        InputError: ``markers X mm (or m) from their nearest neighbour ...``.
    """
    apart = marker_spacing_mm(frame)
    if apart is not None and apart < SPACING_MM[0]:
        raise InputError(f"markers {apart:.3g} mm from their nearest neighbour in the first frame: optical markers are "
                         "millimetres wide, so the take's length unit is wrong (a file in metres read as mm? "
                         'A capture JSON gives its unit in "units")')
    seen = int(np.isfinite(np.asarray(frame, dtype=float)).all(axis=1).sum())
    if apart is not None and apart > SPACING_MM[1] and seen >= REFUSED_FAR_MARKERS:
        raise InputError(f"markers {apart / 1000:.3g} m from their nearest neighbour in the first frame: markers on a "
                         "subject are centimetres apart, so the take's length unit is wrong (a file in mm read as "
                         'metres? A capture JSON gives its unit in "units")')


def take_scale_warning(take: Recording) -> str | None:
    """``scale_warning`` of a labeled take, before anything is labeled or fitted: the spacing
    of its fullest frame, the speed of its own labels (``eval`` and ``model`` read these)."""
    frame, _ = take.fullest_frame()
    unit = take.source.unit if take.source is not None else "mm"
    return scale_warning(take.positions[frame], take.positions, take.rate, unit, names=list(take.names))


def _median_or_nan(values: np.ndarray) -> np.ndarray:
    """Column medians over finite entries; NaN for a column with none (no warning from numpy)."""
    out = np.full(values.shape[1], np.nan)
    seen = np.isfinite(values).any(axis=0)
    out[seen] = np.nanmedian(values[:, seen], axis=0)
    return out


def _most_common(indices: np.ndarray) -> int:
    return int(np.bincount(indices).argmax())


def model_misfit_warning(misfits: list[SegmentMisfit], frame: int) -> str | None:
    """One line naming the model's segments the labeled frame ``frame`` does not fit, or None."""
    if not misfits:
        return None
    worst = ", ".join(f"{m.segment} {m.off_mm:.0f} mm (tolerance {m.tolerance_mm:.0f})" for m in misfits[:4])
    return (f"warning: the labels of frame {frame} do not fit {len(misfits)} of the model's segments ({worst}"
            f"{' ...' if len(misfits) > 4 else ''}): the model may not describe this take (markers placed "
            "otherwise, or segments lumped by a trial with little motion) and may name the markers the labels "
            "leave out wrongly; compare with a labeling without the model")
