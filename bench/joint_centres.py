"""Fitted joint centres against a lab's, on the real takes that carry them, and what the motion determines.

- opensim-core_walking2.c3d: fitted on every marker but the lab's ``*JC`` centres, scored
  against those centres in the frames that have them.
- rajagopal_motion_capture_run.trc: fitted on the run; the lab's centres exist only in the
  static trial, so each is carried into the run by the markers of the segment it is fixed to
  (the pelvis for the hip, the thigh for the knee, the shank for the ankle, the upper arm
  for the elbow), by Kabsch from the static trial's mean frame.

For each joint it prints the median distance, and what an oracle gets that sets the k
weakest directions of the joint's least-squares system (eq. 4 with the poses fixed) to the
lab centre's own: if that stays far above the aim, no choice along the unexcited axis can
reach it, and the disagreement is in the directions the motion does determine.

    .venv/bin/python bench/joint_centres.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from formulations.markers.rigid import rigid_transform  # noqa: E402
from formulations.subject.fit import SubjectFit, fit_subject  # noqa: E402
from formulations.subject.joint_fit import centre_trajectory, joint_system  # noqa: E402
from formulations.subject.segment_fit import fit_segment  # noqa: E402
from service.io.formats import read_labeled  # noqa: E402

DATA = ROOT.parent / "shared" / "data" / "mocap_opensim"
Array = np.ndarray
# lab centre -> a marker on the proximal segment, one on the distal segment
WALKING2 = {"RHJC": ("RASI", "RTH1"), "LHJC": ("LASI", "LTH1"), "RKJC": ("RTH1", "RTB1"),
            "LKJC": ("LTH1", "LTB1"), "RAJC": ("RTB1", "RCAL"), "LAJC": ("LTB1", "LCAL")}
PELVIS = ["LASI", "RASI", "LPSI", "RPSI"]
# in the run, also the markers that carry the static centre (the segment it is fixed to)
RUN = {"RHJC": ("LPSI", "RTH2", PELVIS), "LHJC": ("LPSI", "LTH2", PELVIS),
       "RKJC": ("RTH2", "RTB1", ["RTH1", "RTH2", "RTH3"]), "LKJC": ("LTH2", "LTB1", ["LTH1", "LTH2", "LTH3"]),
       "RAJC": ("RTB1", "RCAL", ["RTB1", "RTB2", "RTB3"]), "LAJC": ("LTB1", "LCAL", ["LTB1", "LTB2", "LTB3"]),
       "REJC": ("RUA1", "RLEL", ["RUA1", "RUA2", "RUA3"]), "LEJC": ("LUA1", "LFAsuperior", ["LUA1", "LUA2", "LUA3"])}


def positions_of(path: Path) -> tuple[list[str], Array]:
    take = read_labeled(path)
    return list(take.names), np.where(take.missing()[:, :, None], np.nan, take.positions)


def segment_of(fit: SubjectFit, marker: str) -> list[str]:
    return next(s.markers for s in fit.model.segments if marker in s.markers)


def report(label: str, names: list[str], positions: Array, fit: SubjectFit, truth: Array, a: str, b: str) -> None:
    """One joint's median distance and the oracle's, with the joint system's relative singular values."""
    seg_a, seg_b = segment_of(fit, a), segment_of(fit, b)
    joint = next((j for j in fit.model.joints if {j.segments[0], j.segments[1]} == {seg_a[0], seg_b[0]}), None)
    if joint is None:
        print(f"{label:5s} no joint between {seg_a[0]} and {seg_b[0]}")
        return
    fitted = float(np.nanmedian(np.linalg.norm(fit.centres[joint.name] - truth, axis=1)))
    if min(len(seg_a), len(seg_b)) < 3:
        print(f"{label:5s} {fitted:6.1f} mm   (a two-marker segment: no oracle)")
        return
    fa, fb = (fit_segment(positions, [names.index(m) for m in s]) for s in (seg_a, seg_b))
    lhs, rhs = joint_system(fa, fb)
    solution = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    seen = fa.valid & fb.valid & np.isfinite(truth).all(axis=1)
    lab = np.concatenate([np.einsum("kji,kj->i", f.rotation[seen], truth[seen] - f.origin[seen]) / seen.sum()
                          for f in (fa, fb)])
    _, singular, axes = np.linalg.svd(lhs, full_matrices=False)
    oracle = []
    for k in (1, 2, 3):
        centre = solution + axes[6 - k:].T @ (axes[6 - k:] @ (lab - solution))
        trajectory, _, _ = centre_trajectory(fa, fb, centre[:3], centre[3:], positions)
        oracle.append(float(np.nanmedian(np.linalg.norm(trajectory - truth, axis=1))))
    lab_fit, _, _ = centre_trajectory(fa, fb, lab[:3], lab[3:], positions)
    floor = float(np.nanmedian(np.linalg.norm(lab_fit - truth, axis=1)))
    print(f"{label:5s} {fitted:6.1f} mm   oracle k=1,2,3: {' '.join(f'{o:5.1f}' for o in oracle)}   "
          f"lab centre fixed in both segments: {floor:4.1f}   singular values {np.round(singular[3:] / singular[0], 3)}")


def walking2() -> None:
    names, positions = positions_of(DATA / "opensim-core_walking2.c3d")
    keep = [i for i, n in enumerate(names) if not n.endswith("JC")]
    fit = fit_subject([names[i] for i in keep], positions[:, keep])
    print("opensim-core_walking2.c3d, fitted without the lab's centres; median distance to them:")
    for label, (a, b) in WALKING2.items():
        report(label, [names[i] for i in keep], positions[:, keep], fit, positions[:, names.index(label)], a, b)


def rajagopal() -> None:
    static_names, static = positions_of(DATA / "rajagopal_static_run.trc")
    names, positions = positions_of(DATA / "rajagopal_motion_capture_run.trc")
    fit = fit_subject(names, positions)
    still = np.nanmean(static, axis=0)
    print("rajagopal_motion_capture_run.trc, lab centres of the static trial carried by their segment:")
    for label, (a, b, markers) in RUN.items():
        source = still[[static_names.index(m) for m in markers]]
        target = positions[:, [names.index(m) for m in markers]]
        weight = np.isfinite(target).all(axis=2).astype(float)
        ok = weight.sum(axis=1) >= 3
        rot, c_s, c_t = rigid_transform(np.broadcast_to(source, target[ok].shape), np.nan_to_num(target[ok]), weight[ok])
        truth = np.full((len(positions), 3), np.nan)
        truth[ok] = np.einsum("kij,kj->ki", rot, still[static_names.index(label)] - c_s) + c_t
        report(label, names, positions, fit, truth, a, b)


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " ")).parse_args()  # --help; no options
    walking2()
    rajagopal()
