#!/usr/bin/python3
"""SIMULATED example inputs for the commands in README.md, docs/ and `errfield <command> --help`.

Writes, in the current directory (or --out-dir), from `errfield simulate` (the paper's set-up: the
ER20-C10 with its ball tool, the 500 mm cube at (750, -250, 350), tool down) and nothing else:

  robot.json     the nominal robot (errfield simulate --robot-out)
  errors.csv     an error field on the paper's 125-point grid (125 mm step, seed 1): point, x,y,z
                 (nominal position, mm), q1..q6 (deg), dL (distance error to the base point at the
                 cube corner, mm: measured distance - nominal distance, the paper's eq. 6) and
                 dx,dy,dz (the simulator's true position, registered onto the nominal positions by a
                 least-squares rigid motion as a tracker registration would, - the nominal position;
                 robot frame, mm)
  scattered.csv  the same columns at 200 random poses in the cube (seed 3)
  targets.csv    64 targets, one random point per grid cell (seed 2): point, x,y,z, q1..q6
  measured.csv   150 scattered poses with up to 30 deg of tool tilt (seed 4), as a tracker measures
                 them (the columns `errfield fit` reads; errfield simulate's own output)
  residuals.csv  what kinematic calibration leaves on measured.csv: point, q1..q6 and ex,ey,ez =
                 tracker reading - the calibrated model's prediction (tracker frame, mm), from
                 `errfield calibrate --model position` and `errfield fk` with the calibrated robot

Every file says it is SIMULATED in its first line. Python 3 standard library only.
Usage: make_example_error_field.py [--errfield PATH] [--out-dir DIR]
"""
import argparse
import csv
import math
import os
import subprocess
import sys


def run(errfield, *args):
    p = subprocess.run([errfield, *args], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"make_example_error_field: 'errfield {' '.join(args)}' failed (exit {p.returncode}):\n{p.stderr}")


def read_rows(path):
    """Header comment lines and the rows (dicts) of an errfield CSV."""
    with open(path, newline="") as f:
        lines = f.read().splitlines()
    comments = [l for l in lines if l.startswith("#")]
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    return comments, rows


def write_rows(path, comment, columns, rows):
    with open(path, "w", newline="") as f:
        f.write("# " + comment + "\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            w.writerow([r[c] if isinstance(r[c], str) else repr(r[c]) for c in columns])


JOINTS = ["q1", "q2", "q3", "q4", "q5", "q6"]


def rigid_fit(moving, fixed):
    """Rotation R (3x3 lists) and translation t minimising sum |R m + t - f|^2 (Horn's quaternion method;
    the largest eigenvector of his 4x4 matrix by power iteration on a positively shifted copy)."""
    n = len(moving)
    cm = [sum(p[k] for p in moving) / n for k in range(3)]
    cf = [sum(p[k] for p in fixed) / n for k in range(3)]
    S = [[sum((m[a] - cm[a]) * (f[b] - cf[b]) for m, f in zip(moving, fixed)) for b in range(3)] for a in range(3)]
    (sxx, sxy, sxz), (syx, syy, syz), (szx, szy, szz) = S
    N = [[sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
         [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
         [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
         [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz]]
    shift = sum(abs(v) for row in N for v in row)
    q = [1.0, 0.0, 0.0, 0.0]
    for _ in range(2000):
        q2 = [sum((N[i][k] + (shift if i == k else 0.0)) * q[k] for k in range(4)) for i in range(4)]
        norm = math.sqrt(sum(v * v for v in q2))
        q = [v / norm for v in q2]
    w, x, y, z = q
    R = [[w*w + x*x - y*y - z*z, 2*(x*y - w*z), 2*(x*z + w*y)],
         [2*(x*y + w*z), w*w - x*x + y*y - z*z, 2*(y*z - w*x)],
         [2*(x*z - w*y), 2*(y*z + w*x), w*w - x*x - y*y + z*z]]
    t = [cf[a] - sum(R[a][b] * cm[b] for b in range(3)) for a in range(3)]
    return R, t


def error_field(simulated_path):
    """Target rows with dL (to base b0) and dx,dy,dz (registered truth - nominal) from a simulate
    --truth-columns file."""
    _, rows = read_rows(simulated_path)
    base = next(r for r in rows if r["kind"] == "base")
    b = [float(base[c]) for c in ("x", "y", "z")]
    targets = [r for r in rows if r["kind"] == "target"]
    # A user sees positions in a frame registered to the robot: fit the truth onto the nominal
    # positions by a rigid motion (as a tracker registration does), so dx,dy,dz hold no frame offset.
    R, tr = rigid_fit([[float(r[c]) for c in ("true_x", "true_y", "true_z")] for r in targets],
                      [[float(r[c]) for c in ("x", "y", "z")] for r in targets])
    out = []
    for r in targets:
        p = [float(r[c]) for c in ("x", "y", "z")]
        raw = [float(r[c]) for c in ("true_x", "true_y", "true_z")]
        t = [sum(R[a][k] * raw[k] for k in range(3)) + tr[a] for a in range(3)]
        row = {c: r[c] for c in ["point", "x", "y", "z"] + JOINTS}
        row["dL"] = float(r["dist_b0"]) - math.dist(p, b)
        row["dx"], row["dy"], row["dz"] = (t[k] - p[k] for k in range(3))
        out.append(row)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--errfield", default="errfield", help="the errfield executable (default: errfield on PATH)")
    ap.add_argument("--out-dir", default=".")
    a = ap.parse_args()
    e = a.errfield
    d = a.out_dir
    os.makedirs(d, exist_ok=True)
    j = lambda name: os.path.join(d, name)
    tmp = [j(".example_grid.csv"), j(".example_scattered.csv"), j(".example_fk.csv")]

    field_columns = ["point", "x", "y", "z"] + JOINTS + ["dL", "dx", "dy", "dz"]
    how = ("errfield simulate --seed {seed} --sample {sample} --truth-columns; dL = dist_b0 - |x,y,z - b0| (mm), "
           "dx,dy,dz = true position registered to the nominal ones by a rigid fit - nominal position (robot frame, mm); made by scripts/make_example_error_field.py")
    run(e, "simulate", "--seed", "1", "--sample", "grid", "--step", "125", "--truth-columns",
        "--robot-out", j("robot.json"), "--out", tmp[0])
    write_rows(j("errors.csv"), "SIMULATED error field (not a real robot): " + how.format(seed=1, sample="grid --step 125"),
               field_columns, error_field(tmp[0]))
    run(e, "simulate", "--seed", "3", "--sample", "random:200", "--truth-columns", "--out", tmp[1])
    write_rows(j("scattered.csv"), "SIMULATED error field (not a real robot): " + how.format(seed=3, sample="random:200"),
               field_columns, error_field(tmp[1]))

    run(e, "simulate", "--seed", "2", "--sample", "cells", "--out", tmp[2])
    _, cells = read_rows(tmp[2])
    write_rows(j("targets.csv"), "SIMULATED targets (not a real robot): errfield simulate --seed 2 --sample cells, "
               "target rows, nominal x,y,z (mm) and q1..q6 (deg); made by scripts/make_example_error_field.py",
               ["point", "x", "y", "z"] + JOINTS, [r for r in cells if r["kind"] == "target"])

    run(e, "simulate", "--seed", "4", "--sample", "scattered:150", "--orientation-spread", "30", "--out", j("measured.csv"))
    run(e, "calibrate", "--robot", j("robot.json"), "--data", j("measured.csv"), "--model", "position",
        "--out", tmp[1] + ".json")
    run(e, "fk", "--input", j("measured.csv"), "--robot", tmp[1] + ".json", "--out", tmp[2])
    _, fk = read_rows(tmp[2])
    residuals = []
    for r in fk:
        if r["kind"] != "target":
            continue
        row = {c: r[c] for c in ["point"] + JOINTS}
        for axis in "xyz":
            row["e" + axis] = float(r["m" + axis]) - float(r["t" + axis])
        residuals.append(row)
    write_rows(j("residuals.csv"), "SIMULATED calibration residuals (not a real robot): errfield simulate --seed 4 "
               "--sample scattered:150 --orientation-spread 30 (measured.csv), errfield calibrate --model position, "
               "errfield fk with the calibrated robot; ex,ey,ez = mx,my,mz - tx,ty,tz (tracker frame, mm); "
               "made by scripts/make_example_error_field.py", ["point"] + JOINTS + ["ex", "ey", "ez"], residuals)
    for t in tmp + [tmp[1] + ".json"]:
        if os.path.exists(t):
            os.remove(t)
    print(f"SIMULATED example inputs written to {os.path.abspath(d)}: robot.json, errors.csv, scattered.csv, "
          "targets.csv, measured.csv, residuals.csv")


if __name__ == "__main__":
    main()
