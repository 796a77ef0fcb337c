#!/usr/bin/python3
"""Tool point transfer study (docs/robot.md, "Tool points and orientation"): a model fitted with the
reflector at point A of the flange, used at point B (`--tool`, or `locate-tool` from 40 readings of
B), scored on held-out readings of B. SIMULATED data: two `errfield simulate` runs with the same
seed and joints, the second with the reflector moved by `--tool-offset` (a fixed offset draws no
random numbers, so the robot's errors, noise and poses are the same; the payload sits at the tool
point, which moves the simulated payload by the offset too - checked below, it is < 0.01 mm).

usage: scripts/tool_point_study.py ERRFIELD WORKDIR [--seeds 1,2,3] [--offsets 150,0,0;0,0,150]
                                   [--spread DEG] [--train 210] [--fits "NAME=FIT OPTIONS;..."]
Prints one table row per fit and offset: held-out RMS at B, 95 % coverage, refused rows, the
kinematic part's RMS at B, and the reference fitted at B itself.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

BOX = "-150,150,-130,-30,70,150,-90,90,-110,110,-180,180"
SIM = f"--robot kr16 --joint-box {BOX} --systematic realistic --joint-decimals 3 --measure positions"
N_ALL, N_TRAIN, N_LOCATE = 300, 210, 40
FITS = [("defaults", ""), ("joint-functions 0", "--joint-functions 0"), ("gravity-load off", "--gravity-load off"),
        ("kinematic", "--method kinematic --outlier-limit 0")]


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r


def must(cmd):
    r = run(cmd)
    if r.returncode:
        sys.exit(" ".join(cmd) + "\n" + r.stdout + r.stderr)
    return r


def rows_of(path):
    lines = [l for l in open(path) if not l.startswith("#")]
    return lines[0], lines[1:]


def write_rows(path, header, rows, drop=("x", "y", "z")):
    cols = header.strip().split(",")
    keep = [i for i, c in enumerate(cols) if c not in drop]
    with open(path, "w") as f:
        f.write(",".join(cols[i] for i in keep) + "\n")
        for r in rows:
            cells = r.rstrip("\n").split(",")
            f.write(",".join(cells[i] for i in keep) + "\n")


def rpy(rx, ry, rz):
    cx, sx, cy, sy, cz, sz = (math.cos(math.radians(rx)), math.sin(math.radians(rx)), math.cos(math.radians(ry)),
                              math.sin(math.radians(ry)), math.cos(math.radians(rz)), math.sin(math.radians(rz)))
    # Rz Ry Rx
    return [[cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
            [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
            [-sy, cy * sx, cy * cx]]


def tool_point(robot_json, offset):
    t = json.load(open(robot_json)).get("tool", {})
    p = [t.get("x_mm", 0.0), t.get("y_mm", 0.0), t.get("z_mm", 0.0)]
    r = rpy(t.get("rx_deg", 0.0), t.get("ry_deg", 0.0), t.get("rz_deg", 0.0))
    return [p[i] + sum(r[i][k] * offset[k] for k in range(3)) for i in range(3)]


def summary(path):
    s = json.load(open(path))
    pos = s["position"]["after"] if s["position"] else {}
    unc = s["uncertainty"] or {}
    return pos.get("rms_mm"), unc.get("coverage95"), s["refused"], s["points"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("errfield")
    ap.add_argument("workdir")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--offsets", default="150,0,0")
    ap.add_argument("--spread", type=float, default=0.0, help="--orientation-spread of the poses (deg; 0: tool down)")
    ap.add_argument("--train", type=int, default=N_TRAIN, help="training poses at A (of 300; at most 260)")
    ap.add_argument("--fits", default=None, help='"NAME=fit options;..." instead of the default four fits')
    a = ap.parse_args()
    fits = FITS if a.fits is None else [tuple(f.split("=", 1)) for f in a.fits.split(";")]
    n_train = a.train
    sim = SIM + (f" --orientation-spread {a.spread:g}" if a.spread > 0 else "")
    E, W = a.errfield, a.workdir
    os.makedirs(W, exist_ok=True)
    results = []
    for seed in a.seeds.split(","):
        A = os.path.join(W, f"s{seed}_A{a.spread:g}.csv")
        robot = os.path.join(W, f"s{seed}_robot.json")
        if not os.path.exists(A):
            must([E, "simulate", "--seed", seed, "--sample", f"scattered:{N_ALL}", *sim.split(), "--truth-columns",
                  "--robot-out", robot, "--out", A])
        header, rows = rows_of(A)
        targets = [r for r in rows if r.split(",")[header.strip().split(",").index("kind")] == "target"]
        trainA, holdA = os.path.join(W, f"s{seed}_A_train{n_train}.csv"), os.path.join(W, f"s{seed}_A_hold.csv")
        write_rows(trainA, header, targets[:n_train], drop=())
        write_rows(holdA, header, targets[N_TRAIN:], drop=())
        models = {}
        for name, opts in fits:
            m = os.path.join(W, f"s{seed}_A{n_train}_{name.replace(' ', '_')}.json")
            if not os.path.exists(m):
                must([E, "fit", "--robot", robot, "--data", trainA, *opts.split(), "--out", m])
            models[name] = m
        for off in a.offsets.split(";"):
            offset = [float(v) for v in off.split(",")]
            tag = "_".join(f"{v:g}" for v in offset)
            B = os.path.join(W, f"s{seed}_B{tag}_{a.spread:g}.csv")
            if not os.path.exists(B):
                must([E, "simulate", "--seed", seed, "--sample", f"scattered:{N_ALL}", *sim.split(), "--truth-columns",
                      "--tool-offset", off, "--out", B])
            hb, rb = rows_of(B)
            cols = hb.strip().split(",")
            tb = [r for r in rb if r.split(",")[cols.index("kind")] == "target"]
            # same robot: the true B point is the true A point plus the (rigid) offset
            ta = targets
            ix = [cols.index(c) for c in ("true_x", "true_y", "true_z")]
            worst = 0.0
            for ra, rb_ in zip(ta, tb):
                pa = [float(ra.split(",")[i]) for i in ix]
                pb = [float(rb_.split(",")[i]) for i in ix]
                worst = max(worst, abs(math.dist(pa, pb) - math.hypot(*offset)))
            trainB, holdB, locB = (os.path.join(W, f"s{seed}_B{tag}_{k}.csv") for k in ("train", "hold", "locate"))
            write_rows(trainB, hb, tb[:N_TRAIN])
            write_rows(holdB, hb, tb[N_TRAIN:])
            write_rows(locB, hb, tb[:N_LOCATE])
            point = tool_point(robot, offset)
            tool = ",".join(f"{v:.6f}" for v in point)
            # reference: fitted at B itself (the robot JSON's tool moved to B)
            rj = json.load(open(robot))
            rj["tool"] = dict(rj.get("tool", {}), x_mm=point[0], y_mm=point[1], z_mm=point[2])
            robotB = os.path.join(W, f"s{seed}_robot_B{tag}.json")
            json.dump(rj, open(robotB, "w"))
            refm = os.path.join(W, f"s{seed}_B{tag}_ref.json")
            if not os.path.exists(refm):
                must([E, "fit", "--robot", robotB, "--data", trainB, "--out", refm])
            sref = os.path.join(W, f"s{seed}_B{tag}_ref.summary.json")
            must([E, "validate", "--model", refm, "--data", holdB, "--summary-out", sref])
            ref = summary(sref)
            for name, m in models.items():
                for how in ("--tool", "locate-tool"):
                    sj = os.path.join(W, f"s{seed}_B{tag}_{name.replace(' ', '_')}_{how.strip('-')}.summary.json")
                    if how == "--tool":
                        r = run([E, "validate", "--model", m, "--data", holdB, "--tool", tool, "--summary-out", sj])
                    else:
                        located = m.replace(".json", f"_B{tag}_located.json")
                        r = run([E, "locate-tool", "--model", m, "--data", locB, "--out", located])
                        if r.returncode == 0:
                            r = run([E, "validate", "--model", located, "--data", holdB, "--summary-out", sj])
                    if r.returncode:
                        results.append((seed, tag, name, how, None, None, None, None, ref, worst, r.stderr.strip()[:160]))
                        continue
                    rms, cov, refused, points = summary(sj)
                    results.append((seed, tag, name, how, rms, cov, refused, points, ref, worst, ""))
    print("seed,offset,fit,tool,rms_B_mm,coverage95,refused,points,ref_rms_B_mm,ref_coverage,sim_offset_dev_mm,error")
    for s, tag, name, how, rms, cov, refused, points, ref, worst, err in results:
        f = lambda v: "" if v is None else f"{v:.4f}"
        print(f"{s},{tag},{name},{how},{f(rms)},{f(cov)},{refused},{points},{f(ref[0])},{f(ref[1])},{worst:.4f},{err}")


if __name__ == "__main__":
    main()
