#!/usr/bin/python3
"""The flange's orientation error (docs/robot.md, "Orientation of the flange"): SIMULATED poses read
with a 6-DoF probe, or at three reflector nests off one line; the first 240 poses train, the other
200 are held out. Prints per case and seed the held-out orientation error before/after (mdeg RMS),
the share of poses within the model's own 95 % radius of the rotation, the mean NEES (3 expected)
and the position error after (mm RMS) with its coverage.

usage: scripts/orientation_study.py ERRFIELD WORKDIR [--seeds 1,2,3] [--robots kr16,ur5e]
"""
import argparse
import csv
import json
import os
import sys

from flange_points_study import read_split, run  # run: a command, its output kept for the error

N_POSES, N_TRAIN = 440, 240
CASES = {
    "probe 10 mdeg": ["--probe", "0,0,100,180,0,0", "--probe-noise", "10"],
    "probe 3 mdeg": ["--probe", "0,0,100,180,0,0", "--probe-noise", "3"],
    "three nests": ["--reflectors", "0,0,100;150,0,100;0,150,100"],
}


def split(source, workdir):
    rows, fields, train = read_split(source, N_TRAIN)
    for name, training in (("train.csv", True), ("test.csv", False)):
        with open(os.path.join(workdir, name), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
            w.writeheader()
            w.writerows(r for r in rows if (r["point"] in train) == training)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("errfield")
    p.add_argument("workdir")
    p.add_argument("--seeds", default="1,2,3")
    p.add_argument("--robots", default="kr16,ur5e")
    a = p.parse_args()
    os.makedirs(a.workdir, exist_ok=True)
    print("case | robot | seed | orientation before / after (mdeg RMS) | coverage95 | mean NEES | position after (mm RMS) | coverage95")
    for robot in a.robots.split(","):
        for case, options in CASES.items():
            for seed in a.seeds.split(","):
                d = a.workdir
                run([a.errfield, "simulate", "--robot", robot, "--seed", seed, "--sample", f"scattered:{N_POSES}",
                     "--orientation-spread", "30", "--measure", "positions", "--systematic", "realistic", *options,
                     "--robot-out", os.path.join(d, "robot.json"), "--out", os.path.join(d, "all.csv")])
                with open(os.path.join(d, "robot.json")) as f:
                    description = json.load(f)
                description["tool"] = {"x_mm": 0, "y_mm": 0, "z_mm": 100, "rx_deg": 0, "ry_deg": 0, "rz_deg": 0}
                with open(os.path.join(d, "robot_tool.json"), "w") as f:
                    json.dump(description, f)
                split(os.path.join(d, "all.csv"), d)
                run([a.errfield, "fit", "--robot", os.path.join(d, "robot_tool.json"), "--data",
                     os.path.join(d, "train.csv"), "--out", os.path.join(d, "m.json")])
                run([a.errfield, "validate", "--model", os.path.join(d, "m.json"), "--data", os.path.join(d, "test.csv"),
                     "--summary-out", os.path.join(d, "s.json")])
                with open(os.path.join(d, "s.json")) as f:
                    s = json.load(f)
                o = s["orientation"]
                print(f"{case} | {robot} | {seed} | {o['before']['rms_mdeg']:.1f} / {o['after']['rms_mdeg']:.1f} | "
                      f"{o['coverage95']:.3f} | {o['mean_nees']:.2f} | {s['position']['after']['rms_mm']:.4f} | "
                      f"{s['uncertainty']['coverage95']:.3f}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
