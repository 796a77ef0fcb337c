#!/usr/bin/python3
"""Which sign do the UR5/WAM files of ../shared/realdata/ur5-wam-jacobi give their *_dif columns?

Independent of errfield (numpy and scipy only; run with /usr/bin/python3 from the repository's
root). The data set says *_dif is "the difference between target and achieved position", which does
not say measured = target + dif or target - dif, and the nominal kinematics cannot tell: to first
order a kinematic error and its negative are equally kinematic. Two things can:

1. the second-order terms of a kinematic fit: a full standard D-H calibration (every link's a, d,
   alpha, theta offset, the tool point, a rigid motion) leaves less to the right sign; the WAM's
   errors are 7x the UR5's, so there these terms are ~50x larger;
2. gravity: with a compliance angle per joint proportional to the gravity torque of a load at the
   tool point, the right sign makes the arm sag (positive compliances), the wrong one rise.

Prints both for both robots. docs/realdata.md quotes the output; --preset ur5-jacobi uses
measured = target + dif.
"""
import csv
import os
import sys

import numpy as np
from scipy.optimize import least_squares

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "realdata", "ur5-wam-jacobi")
PI = np.pi
# Standard D-H (a, d mm; alpha rad): UR's CB3 UR5 table, Barrett's WAM table.
ROBOTS = {
    "UR5": dict(file="UR5/3D_UR5_uncalibrated_grid_cleaned.csv", joints=6,
                a=[0, -425, -392.25, 0, 0, 0], d=[89.159, 0, 0, 109.15, 94.65, 82.3],
                alpha=[PI / 2, 0, 0, PI / 2, -PI / 2, 0], tool=[0, 0, 31.0]),
    "WAM": dict(file="WAM/3D_WAM_uncalibrated_grid_cleaned.csv", joints=7,
                a=[0, 0, 45, -45, 0, 0, 0], d=[0, 0, 550, 0, 300, 0, 60],
                alpha=[-PI / 2, PI / 2, -PI / 2, PI / 2, -PI / 2, PI / 2, 0], tool=None),
}


def load(path, n):
    rows = list(csv.DictReader(open(path)))
    q = np.array([[float(r["joint_%d" % i]) for i in range(1, n + 1)] for r in rows])
    t = np.array([[float(r[k]) for k in ("x_t", "y_t", "z_t")] for r in rows])
    d = np.array([[float(r[k]) for k in ("x_dif", "y_dif", "z_dif")] for r in rows])
    return q, t, d


def fk(p, q_deg, tool, frames=None):
    n, joints = q_deg.shape
    T = np.tile(np.eye(4), (n, 1, 1))
    for i in range(joints):
        if frames is not None:
            frames.append(T.copy())
        a, d, al, th0 = p[4 * i:4 * i + 4]
        th = np.radians(q_deg[:, i]) + th0
        ct, st, ca, sa = np.cos(th), np.sin(th), np.cos(al), np.sin(al)
        A = np.zeros((n, 4, 4))
        A[:, 0, 0], A[:, 0, 1], A[:, 0, 2], A[:, 0, 3] = ct, -st * ca, st * sa, a * ct
        A[:, 1, 0], A[:, 1, 1], A[:, 1, 2], A[:, 1, 3] = st, ct * ca, -ct * sa, a * st
        A[:, 2, 1], A[:, 2, 2], A[:, 2, 3], A[:, 3, 3] = sa, ca, d, 1
        T = T @ A
    return T[:, :3, :3] @ tool + T[:, :3, 3]


def rot(w):
    th = np.linalg.norm(w)
    if th < 1e-12:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def main():
    if not os.path.isdir(ROOT):
        sys.exit("no data at " + ROOT)
    for name, r in ROBOTS.items():
        n = r["joints"]
        q, t, dif = load(os.path.join(ROOT, r["file"]), n)
        p0 = np.array(sum([[r["a"][i], r["d"][i], r["alpha"][i], 0.0] for i in range(n)], []))
        tool0 = np.array(r["tool"] if r["tool"] else [0, 0, 0.0])
        if r["tool"] is None:  # the WAM's tool point: located on the commanded positions
            fit = least_squares(lambda x: (fk(p0, q, x[:3]) @ rot(x[3:6]).T + x[6:9] - t).ravel(), np.zeros(9))
            tool0 = fit.x[:3]
        frames = []
        nominal = fk(p0, q, tool0, frames)
        print("%s: %d poses, nominal FK vs commanded: largest %.4f mm; mean |dif| %.3f mm" % (
            name, len(q), np.abs(np.linalg.norm(nominal - t, axis=1)).max(), np.linalg.norm(dif, axis=1).mean()))
        levers = []
        for j in range(1, n):
            z, o = frames[j][:, :3, 2], frames[j][:, :3, 3]
            levers.append(np.einsum("ij,ij->i", np.cross(nominal - o, np.array([0, 0, -1.0])), z) / 1000)
        scale = np.r_[np.tile([1, 1, 1e-3, 1e-3], n), 1, 1, 1, 1e-3, 1e-3, 1e-3, 1, 1, 1]
        for sign in (+1, -1):
            measured = t + sign * dif

            def residual(x, compliant):
                qq = q.copy()
                if compliant:
                    for k, lever in enumerate(levers):
                        qq[:, k + 1] += np.degrees(x[len(scale) + k] * lever)
                p = p0 + x[:4 * n]
                tool = tool0 + x[4 * n:4 * n + 3]
                return (fk(p, qq, tool) @ rot(x[4 * n + 3:4 * n + 6]).T + x[4 * n + 6:4 * n + 9] - measured).ravel()

            kin = least_squares(residual, np.zeros(len(scale)), x_scale=scale, args=(False,))
            rms = np.sqrt((kin.fun.reshape(-1, 3) ** 2).sum(1).mean())
            comp = least_squares(residual, np.zeros(len(scale) + len(levers)),
                                 x_scale=np.r_[scale, [1e-3] * len(levers)], args=(True,))
            k = comp.x[len(scale):] * 1e3
            print("  measured = target %s dif: kinematic fit RMS %.5f mm; gravity compliances of joints 2..%d "
                  "(mrad per m of lever, + = sags): %s" % ("+" if sign > 0 else "-", rms, n,
                                                           " ".join("%.2f" % v for v in k)))


if __name__ == "__main__":
    main()
