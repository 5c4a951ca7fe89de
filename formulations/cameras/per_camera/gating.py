"""How ``per-camera`` association gates, prices and checks its candidates."""

from __future__ import annotations

from dataclasses import dataclass, field

from formulations.markers.guide import Gate


@dataclass(frozen=True)
class PerCameraGating:
    """How per-camera candidates are gated and priced, and views checked across cameras.

    Attributes:
        gate: Gate radius of the guide's frame-by-frame assignment around the prediction,
            mm at the marker's depth (its base radius is the guide's miss cost).
        window_gate: Gate radius of the window's candidates. Tighter than ``gate`` for a
            marker seen last frame: its image-plane prediction is good to a few mm (on
            CMU 85_02 through the Pose2Sim rig, 99.99 % of its own detections lie within
            25 mm, all within 43 mm), and every further candidate joins neighbouring
            markers into one LP component: 30 mm halves the window LP's time there.
        prediction_weight: w_p, cost per sigma between a candidate and the prediction.
        prediction_sigma_mm: sigma_0, uncertainty of a prediction for a marker seen last frame.
        prediction_sigma_growth_mm: sigma_1, added per frame unseen.
        prediction_cap_sigmas: cap, in sigmas, beyond which the prediction term stops growing.
        max_reprojection_px: tau, the largest reprojection error of a view kept when the
            cameras' assignments are triangulated (``per_camera_locate``).
        max_shape_mm: s_max, the largest deviation from the learned neighbour distances of
            a second view found for a marker left with one (``per_camera_reacquire``).
        max_pair_shape_mm: The same limit for a point two cameras agree on: above it the
            pair is taken for a chance meeting of rays and split (``per_camera_reacquire``).
    """

    gate: Gate = field(default_factory=Gate)
    window_gate: Gate = field(default_factory=lambda: Gate(radius_mm=30.0))
    prediction_weight: float = 2.0
    prediction_sigma_mm: float = 4.0
    prediction_sigma_growth_mm: float = 2.5
    prediction_cap_sigmas: float = 6.0
    max_reprojection_px: float = 2.0
    max_shape_mm: float = 20.0
    max_pair_shape_mm: float = 60.0
