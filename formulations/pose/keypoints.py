"""2D keypoints as a weighting function: the confidence-weighted reprojection error of the model's joints.

For camera c, keypoint k with detection u_ck and confidence c_ck (0 = not detected), and the
model joint named like that keypoint projecting to p_ck(X),

    Sigma^k_c(X) = sum_k c_ck rho(|p_ck(X) - u_ck|) / sum_k c_ck,   rho(d) = log(1 + d^2 / sigma^2),

and E(X) = sum_c Sigma^k_c(X) (eq. 5's sum over cameras). rho is Cauchy's: quadratic for
errors below sigma, logarithmic beyond, so a keypoint put on the wrong limb or person pulls
without dominating. A camera without detections adds nothing.

For a local refinement (``refine``) the same data give residuals, one per seen keypoint and image
axis, f = sqrt(c_ck / sum_k c_ck) (p_ck(X) - u_ck) / sigma: under a Cauchy loss rho(f^2) = log(1 + f^2)
summed over both axes they approximate the energy above (equal to first order for small errors).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from formulations.cameras.rig import Rig
from formulations.errors import FormulationError
from formulations.pose.body import BodyModel
from formulations.pose.kinematics import Posed
from formulations.pose.rotation import Array

# OpenPose BODY_25B keypoint order (Pose2Sim's skeletons.py).
BODY_25B = (
    "Nose", "LEye", "REye", "LEar", "REar", "LShoulder", "RShoulder", "LElbow", "RElbow", "LWrist",
    "RWrist", "LHip", "RHip", "LKnee", "RKnee", "LAnkle", "RAnkle", "Neck", "Head", "LBigToe",
    "LSmallToe", "LHeel", "RBigToe", "RSmallToe", "RHeel",
)


@dataclass(frozen=True)
class KeypointPairs:
    """Which model nodes carry which keypoints: ``nodes[i]`` is named ``BODY_25B[keypoints[i]]``."""

    nodes: Array
    keypoints: Array

    @staticmethod
    def of(model: BodyModel, names: tuple[str, ...] = BODY_25B) -> KeypointPairs:
        pairs = [(n, names.index(node.name)) for n, node in enumerate(model.nodes) if node.name in names]
        if not pairs:
            raise FormulationError(f"keypoints: no joint of the model is named like a keypoint ({', '.join(names[:6])}, ...)")
        nodes, keypoints = zip(*pairs)
        return KeypointPairs(np.array(nodes), np.array(keypoints))


@dataclass(frozen=True)
class KeypointMeasurement:
    """One frame's detections ``(C, K, 3)`` (x, y, confidence) for a rig's C cameras, sigma in pixels."""

    rig: Rig
    pairs: KeypointPairs
    detections: Array
    sigma: float = 15.0

    @property
    def empty(self) -> bool:
        return not bool((self._confidence() > 0).any())

    def _confidence(self) -> Array:
        confidence: Array = np.nan_to_num(self.detections[:, self.pairs.keypoints, 2])
        return confidence

    def residuals(self, posed: Posed) -> Array:
        """``(N, R)`` the module doc's residuals f for N posed particles, R = 2 x the seen keypoints."""
        count = len(posed.positions)
        parts = [np.empty((count, 0))] + [
            (offset * np.sqrt(weight)[:, None] / self.sigma).reshape(count, -1) for offset, weight in self._offsets(posed)
        ]
        residuals: Array = np.concatenate(parts, axis=1)
        return residuals

    def energy(self, posed: Posed) -> Array:
        """``(N,)`` E(X) of the module doc for N posed particles."""
        total = np.zeros(len(posed.positions))
        for offset, weight in self._offsets(posed):
            total += np.log1p((offset ** 2).sum(axis=2) / self.sigma ** 2) @ weight
        return total

    def _offsets(self, posed: Posed) -> Iterator[tuple[Array, Array]]:
        """Per camera that sees a keypoint: ``(N, S, 2)`` p_ck(X) - u_ck over its S seen keypoints,
        and their weights c_ck / sum_k c_ck."""
        joints = posed.positions[:, self.pairs.nodes]
        confidence = self._confidence()
        for c in np.flatnonzero(confidence.sum(axis=1) > 0):
            seen = confidence[c] > 0
            pixels = self.rig.cameras[c].project(joints[:, seen].reshape(-1, 3)).reshape(len(joints), -1, 2)
            yield pixels - self.detections[c, self.pairs.keypoints[seen], :2], confidence[c, seen] / confidence[c, seen].sum()
