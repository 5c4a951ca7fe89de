"""How ``per-camera`` association gates, prices and checks its candidates."""

from __future__ import annotations

from dataclasses import dataclass, field

from formulations.guide import Gate


@dataclass(frozen=True)
class PerCameraGating:
    """How per-camera candidates are gated and priced, and views checked across cameras.

    Attributes:
        gate: Gate radius around the prediction, mm at the marker's depth.
        prediction_weight: w_p, cost per sigma between a candidate and the prediction.
        prediction_sigma_mm: sigma_0, uncertainty of a prediction for a marker seen last frame.
        prediction_sigma_growth_mm: sigma_1, added per frame unseen.
        prediction_cap_sigmas: cap, in sigmas, beyond which the prediction term stops growing.
        max_reprojection_px: tau, the largest reprojection error of a view kept when the
            cameras' assignments are triangulated (``per_camera_locate``).
        max_shape_mm: s_max, the largest deviation from the learned neighbour distances of
            a second view found for a marker left with one (``per_camera_reacquire``).
    """

    gate: Gate = field(default_factory=Gate)
    prediction_weight: float = 2.0
    prediction_sigma_mm: float = 4.0
    prediction_sigma_growth_mm: float = 2.5
    prediction_cap_sigmas: float = 6.0
    max_reprojection_px: float = 2.0
    max_shape_mm: float = 20.0
