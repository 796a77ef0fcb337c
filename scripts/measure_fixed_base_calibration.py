#!/usr/bin/env python3
"""Effect of kinematic calibration from distances to FIXED base points (SIMULATED data).

Protocol (docs/robot.md, "Fixed base points"): `errfield simulate --seed 1` on the paper cube (125 mm
grid, tool-down) measuring distances to 1 or 3 fixed points (true positions below); `errfield
calibrate --model distance --base-point ...` from nominal points off by about 1 mm; validation on 64
random cube targets of a second run (--seed 2, --truth-columns): the identified model's FK against
the simulator's true positions (3-D error after the best-fit rigid motion, i.e. what is left once the
cell frame is registered) and the distance to each fixed point (frame-free, what the tracker sees).
Usage: measure_fixed_base_calibration.py path/to/errfield [workdir]
"""
import re
import subprocess
import sys
import tempfile

import numpy as np

TRUE = [(1500, 650, 150), (600, -700, 250), (1300, -500, 1100)]
OFFSET = [(0.8, -0.5, 1.1), (-1.2, 0.4, 0.6), (0.3, 0.9, -0.7)]


def run(args):
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"measure_fixed_base_calibration: {' '.join(args)} failed (exit {p.returncode}):\n{p.stderr}")
    return p.stdout


NUMBER = r"(-?[0-9]+(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?)"


def report_field(report, pattern, what):
    """The first group of pattern in calibrate's report; a clear error (not a traceback) when the
    report's wording changed, so the docs test that runs this script names what to update."""
    m = re.search(pattern, report, re.MULTILINE)
    if not m:
        sys.exit(f"measure_fixed_base_calibration: calibrate's report has no {what} (pattern {pattern!r}); "
                 f"update this script. The report:\n{report}")
    return m.group(1)


def identified_points(report, count):
    """Identified coordinates of the fixed points from the report lines 'fixed base point k ...: x V ... y V ... z V'."""
    points = []
    for k in range(count):
        line = report_field(report, rf"^(fixed base point {k}\b.*)$", f"line for fixed base point {k}")
        xyz = re.search(rf"\bx\s+{NUMBER}.*?\by\s+{NUMBER}.*?\bz\s+{NUMBER}", line)
        if not xyz:
            sys.exit(f"measure_fixed_base_calibration: cannot read x, y, z from: {line}")
        points.append(np.array([float(v) for v in xyz.groups()]))
    return points


def read_csv(path):
    lines = [l for l in open(path) if not l.startswith("#")]
    head = lines[0].strip().split(",")
    rows = [l.strip().split(",") for l in lines[1:]]
    return {h: [r[i] for r in rows] for i, h in enumerate(head)}


def kabsch_residual(a, b):
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1, 1, d]) @ u.T
    return np.linalg.norm((a - ca) @ r.T + cb - b, axis=1)


def main():
    exe = sys.argv[1]
    wd = sys.argv[2] if len(sys.argv) > 2 else tempfile.mkdtemp()
    run([exe, "simulate", "--seed", "2", "--sample", "random:64", "--measure", "positions", "--truth-columns",
         "--robot-out", f"{wd}/robot.json", "--out", f"{wd}/val.csv"])
    val = read_csv(f"{wd}/val.csv")
    q = "q1,q2,q3,q4,q5,q6\n" + "\n".join(",".join(val[f"q{j}"][i] for j in range(1, 7)) for i in range(len(val["q1"])))
    open(f"{wd}/valq.csv", "w").write(q + "\n")
    truth = np.array([[float(x) for x in val[c]] for c in ("true_x", "true_y", "true_z")]).T

    def predict(model):
        run([exe, "fk", "--input", f"{wd}/valq.csv", "--robot", model, "--out", f"{wd}/fk.csv"])
        fk = read_csv(f"{wd}/fk.csv")
        return np.array([[float(x) for x in fk[c]] for c in ("x", "y", "z")]).T

    print("| fixed points | model | 3-D error after rigid fit, rms / max (mm) | distance-to-point error, rms / max (mm) |")
    print("|---|---|---|---|")
    for count in (1, 3):
        sim = [exe, "simulate", "--seed", "1", "--measure", "distances", "--out", f"{wd}/fx{count}.csv"]
        cal = [exe, "calibrate", "--robot", f"{wd}/robot.json", "--data", f"{wd}/fx{count}.csv", "--out",
               f"{wd}/cal{count}.json"]
        for k in range(count):
            sim += ["--fixed-base", ",".join(str(v) for v in TRUE[k])]
            cal += ["--base-point", ",".join(f"{t + o:g}" for t, o in zip(TRUE[k], OFFSET[k]))]
        run(sim)
        report = run(cal)
        ident = identified_points(report, count)
        nominal_pts = [np.array(TRUE[k]) + np.array(OFFSET[k]) for k in range(count)]
        for name, model, pts in (("nominal", f"{wd}/robot.json", nominal_pts), ("calibrated", f"{wd}/cal{count}.json", ident)):
            p = predict(model)
            e3 = kabsch_residual(p, truth)
            ed = np.concatenate([np.linalg.norm(p - pts[k], axis=1) - np.linalg.norm(truth - np.array(TRUE[k]), axis=1)
                                 for k in range(count)])
            print(f"| {count} | {name} | {np.sqrt(np.mean(e3**2)):.3f} / {e3.max():.3f} | "
                  f"{np.sqrt(np.mean(ed**2)):.3f} / {np.abs(ed).max():.3f} |")
        kept = report_field(report, r"identified parameters \((\d+)\)", "'identified parameters (N)'")
        removed = report_field(report, r"removed candidates \((\d+)\)", "'removed candidates (N)'")
        removed_points = len(re.findall(r"^\s+base point \d+ [xyz]:", report, re.MULTILINE))
        cond = report_field(report, rf"^condition number.*:\s*{NUMBER}\s*$", "'condition number ...: C' line")
        status = report_field(report, r"^status:\s*(.*)$", "'status:' line")
        print(f"|   | ({count} point(s): {kept} robot parameters + {3 * count - removed_points} point coordinates kept, "
              f"{removed} candidates removed, condition {float(cond):.0f}; {status}) | | |")


    # Reference: the paper's protocol (base point = the robot position at the cube corner).
    run([exe, "simulate", "--seed", "1", "--measure", "distances", "--out", f"{wd}/pair.csv"])
    run([exe, "calibrate", "--robot", f"{wd}/robot.json", "--data", f"{wd}/pair.csv", "--out", f"{wd}/cal_pair.json"])
    e3 = kabsch_residual(predict(f"{wd}/cal_pair.json"), truth)
    print(f"| robot-position base (cube corner) | calibrated | {np.sqrt(np.mean(e3**2)):.3f} / {e3.max():.3f} | — |")


if __name__ == "__main__":
    main()
