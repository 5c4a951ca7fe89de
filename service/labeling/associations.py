"""The chain of each input mode (``service.labeling.loop``): 3D points, cross-camera 3D points,
or per-camera images; each assembles its windows' outcomes into trajectories."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from formulations.cameras.rig import Rig
from formulations.markers.cloud_candidates import CloudGating
from service.capture.capture import Capture, LabelingOptions
from service.capture.reprojection import frame0_pixel_sigma
from service.errors import InputError
from service.io.recording import LabeledTrajectories, UnlabeledCloud
from service.labeling.cloud import CloudChain
from service.labeling.joint_3d import Joint3dChain, cross_camera_cloud, matcher_gates
from service.labeling.loop import WindowChain
from service.labeling.outcome import WindowOutcome
from service.labeling.per_camera import PerCameraChain


class Association(WindowChain[Any], Protocol):
    """A per-window chain, and what its windows' outcomes assemble into."""

    def assemble(self, outcomes: list[WindowOutcome]) -> LabeledTrajectories: ...

    def views(self, outcomes: list[WindowOutcome]) -> np.ndarray: ...


def association_chain(capture: Capture, options: LabelingOptions, look_ahead: bool) -> Association:
    """The chain of the capture's input mode and the chosen association; ``look_ahead``
    False (a frame-by-frame baseline) keeps later frames out of the expected steps."""
    # A frame-by-frame baseline sees no later frame: no median step over them, no unnamed
    # track told from them (a birth is followed three frames).
    gating = CloudGating() if look_ahead else CloudGating(step_median_frames=0, unnamed_tracks=False)
    if capture.points is not None:
        if options.association != "joint-3d":  # the default; a choice made for cameras must not pass unsaid
            raise InputError(f"association {options.association!r} applies to camera captures; this capture is 3D points")
        cloud = UnlabeledCloud(points=capture.points, rate=capture.rate)
        return CloudChain(cloud, capture.names, capture.first_frame, gating, layout_weight=options.layout_weight,
                          unnamed_markers=capture.unnamed_markers)
    cameras, detections = capture.camera_frames()
    if options.association == "per-camera":
        return PerCameraChain(capture.names, capture.first_frame, capture.rate, Rig.of(cameras), detections)
    if options.association != "joint-3d":
        raise InputError(f"association {options.association!r} is not available; use joint-3d or per-camera")
    gates = matcher_gates(frame0_pixel_sigma(capture.frame0_distances()))
    cloud, matched = cross_camera_cloud(cameras, detections, capture.rate, *gates)
    return Joint3dChain(
        cloud, capture.names, capture.first_frame, gating, layout_weight=options.layout_weight, matched=matched,
        rig=Rig.of(cameras), detections=detections,
    )
