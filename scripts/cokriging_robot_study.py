#!/usr/bin/env python3
"""Does cokriging under a fitted LMC beat the shared model on a robot's 3-D error field?

On SIMULATED robots (errfield simulate: scattered poses, 30 deg orientation spread, joints to 3
decimals, realistic systematic effects), for each robot and seed:
  1. simulate N poses and `fit` (kinematic calibration + joint-space kriging) on all of them; the
     field the kriging sees (joints q1..q6 in deg, residuals ex,ey,ez in mm after calibration) is
     taken from the model JSON;
  2. split it into the first 70 % (training) and the rest (held out);
  3. predict the held-out residuals from the training ones with
       - the shared model (the pipeline's REML fit: one variogram, ARD in joint space, for all
         three components), `interpolate --method kriging --model TEXT`;
       - an LMC fitted by `fit-variogram --lmc` to the training poses' direct and cross variograms,
         with the shared model's structures, ranges and ARD map as template (Goulard-Voltz),
         by cokriging: `interpolate --method kriging --model lmc.json`;
       - the same LMC with its cross terms zeroed (each component kriged alone with its own
         direct variogram), to separate the cross-covariances from the per-component sills;
  4. print the held-out RMS per component and in 3-D, and the mean of (error^2 / variance) per
     component (about 1 when the variance is right).

Usage: cokriging_robot_study.py ERRFIELD [--runs kr16:1,kr16:2,ur5e:1,er20-c10:1] [--poses 1000]
(about 1 minute per run on 2 cores).
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np


def run(errfield, *args):
    r = subprocess.run([errfield, *args], capture_output=True, text=True)
    if r.returncode:
        sys.exit(f"errfield {' '.join(args)} failed:\n{r.stderr}")
    return r.stdout


def score(pred_file, truth):
    with open(pred_file) as f:  # the SIMULATED label is a '#' line before the header
        rows = list(csv.reader(line for line in f if not line.startswith("#")))
    p = {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}
    pred = np.column_stack([p["pred_ex"], p["pred_ey"], p["pred_ez"]])
    # var_<col> (the shared model's variance is the same for the three components)
    var = np.column_stack([p["var_ex"], p["var_ey"], p["var_ez"]])
    err = pred - truth
    rms = np.sqrt((err ** 2).mean(0))
    return rms, np.sqrt((err ** 2).sum(1).mean()), (err ** 2 / var).mean(0)


def one_run(errfield, robot, seed, poses, work):
    tag = os.path.join(work, f"{robot}_s{seed}")
    run(errfield, "simulate", "--robot", robot, "--sample", f"scattered:{poses}", "--orientation-spread", "30",
        "--joint-decimals", "3", "--systematic", "realistic", "--seed", str(seed), "--robot-out", tag + "_robot.json",
        "--out", tag + "_all.csv")
    run(errfield, "fit", "--robot", tag + "_robot.json", "--data", tag + "_all.csv", "--out", tag + "_m.json")
    field = json.load(open(tag + "_m.json"))["field"]
    shared = field["variance_calibration"]["model_before"] if "variance_calibration" in field else field["model"]
    q = np.array(field["samples"]["joints_deg"])
    e = np.array(field["values"])
    n_train = int(0.7 * len(q))
    header = ["point", "q1", "q2", "q3", "q4", "q5", "q6", "ex", "ey", "ez"]
    for name, rows in (("train", range(n_train)), ("test", range(n_train, len(q)))):
        with open(f"{tag}_{name}.csv", "w", newline="") as f:
            f.write(f"# SIMULATED residual field (errfield simulate --robot {robot} --seed {seed}; after calibration)\n")
            w = csv.writer(f)
            w.writerow(header)
            for i in rows:
                w.writerow([i + 1] + [repr(v) for v in q[i]] + [repr(v) for v in e[i]])
    truth = e[n_train:]
    common = ["--samples", tag + "_train.csv", "--targets", tag + "_test.csv", "--coords", "q1,q2,q3,q4,q5,q6",
              "--value", "ex,ey,ez"]
    results = []
    run(errfield, "interpolate", "--method", "kriging", "--model", shared, *common, "--out", tag + "_shared.csv")
    results.append(("shared model (REML)", score(tag + "_shared.csv", truth)))
    # The template: the shared model's structures, ranges and map (its sills are ignored).
    template = shared
    run(errfield, "fit-variogram", "--lmc", "--input", tag + "_train.csv", "--coords", "q1,q2,q3,q4,q5,q6",
        "--value", "ex,ey,ez", "--model", template, "--out", tag + "_lmc.json")
    run(errfield, "interpolate", "--method", "kriging", "--model", tag + "_lmc.json", *common, "--out", tag + "_cok.csv")
    results.append(("cokriging, fitted LMC", score(tag + "_cok.csv", truth)))
    lmc = json.load(open(tag + "_lmc.json"))
    for s in lmc["structures"]:
        s["sills"] = [[v if i == j else 0.0 for j, v in enumerate(row)] for i, row in enumerate(s["sills"])]
    json.dump(lmc, open(tag + "_diag.json", "w"))
    run(errfield, "interpolate", "--method", "kriging", "--model", tag + "_diag.json", *common, "--out", tag + "_diag.csv")
    results.append(("LMC without cross terms", score(tag + "_diag.csv", truth)))
    return n_train, len(q) - n_train, results


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("errfield")
    ap.add_argument("--runs", default="kr16:1,kr16:2,ur5e:1,er20-c10:1")
    ap.add_argument("--poses", type=int, default=1000)
    a = ap.parse_args()
    print("SIMULATED robots; held-out RMS of the residual field in mm; z2 = mean error^2 / variance")
    print("| robot | seed | model | ex | ey | ez | 3-D | z2 ex, ey, ez |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for item in a.runs.split(","):
            robot, seed = item.split(":")
            n_train, n_test, results = one_run(a.errfield, robot, int(seed), a.poses, work)
            for label, (rms, rms3, z2) in results:
                print(f"| {robot} | {seed} | {label} | {rms[0]:.4f} | {rms[1]:.4f} | {rms[2]:.4f} | {rms3:.4f} | "
                      f"{z2[0]:.2f}, {z2[1]:.2f}, {z2[2]:.2f} |", flush=True)


if __name__ == "__main__":
    main()
