#!/usr/bin/python3
"""Joint error functions study (docs/robot.md, "Joint error functions"): held-out 3-D RMS, 95 %
coverage and mean NEES of `errfield fit` (kinematic+kriging) with `--joint-functions` of several
degrees, on SIMULATED data sets that `errfield simulate` makes here, and on the training sets of
plan studies (scripts/plan_study.py work directories).

usage: scripts/joint_functions_study.py ERRFIELD WORKDIR [--degrees 0,4,6,8,10,12]
       [--plan-dirs DIR,DIR...] [--fit-extra "fit options"] [--fits NAME]
--fit-extra is passed to every fit except degree 0's (e.g. "--gravity-load off"); --fits names the
folder of WORKDIR its fits go to (default "fits"), so runs with other options keep the data sets.
Writes WORKDIR/fits/joint_functions.csv (one row per set and degree) and prints, per group of sets, the
geometric mean of the RMS ratio to degree 0, the worst ratio and the mean coverage.
"""
import argparse
import csv
import glob
import json
import math
import os
import re
import subprocess
import sys
from collections import defaultdict
from concurrent.futures import ThreadPoolExecutor

BOX = "-150,150,-130,-30,70,150,-90,90,-110,110,-180,180"
# name, training targets, all targets, simulate options (seed 11)
SETS = [
    ("kr16none", 240, 540, f"--robot kr16 --joint-box {BOX} --systematic none --orientation-spread 30 --joint-decimals 3"),
    ("kr16cfg", 240, 540, f"--robot kr16 --joint-box {BOX} --orientation-spread 30 --joint-decimals 3"),
    ("kr16comp", 240, 540, f"--robot kr16 --joint-box {BOX} --systematic none --compliance 1 --orientation-spread 30 "
                           "--joint-decimals 3"),
    ("kr16out", 240, 540, f"--robot kr16 --joint-box {BOX} --systematic realistic --outliers 0.02:3 "
                          "--orientation-spread 30 --joint-decimals 2 --tool-offset random:20"),
    ("kr16r80", 80, 380, f"--robot kr16 --joint-box {BOX} --systematic realistic --orientation-spread 30 --joint-decimals 3"),
    ("kr16r40", 40, 340, f"--robot kr16 --joint-box {BOX} --systematic realistic --orientation-spread 30 --joint-decimals 3"),
    ("ur5ereal", 240, 540, "--robot ur5e --systematic realistic --orientation-spread 30 --joint-decimals 3"),
    ("ur5ecfg", 120, 420, "--robot ur5e --orientation-spread 20 --joint-decimals 2 --tool-offset random:20"),
    ("er20cube", 240, 540, "--orientation-spread 20 --joint-decimals 3"),
    ("er20real", 240, 540, "--systematic realistic --orientation-spread 20 --joint-decimals 3"),
]


def run(cmd):
    return subprocess.run(cmd, capture_output=True, text=True)


def make_set(E, W, name, n_train, n_all, options):
    robot, train, hold = (os.path.join(W, f"{name}.{k}") for k in ("robot.json", "train.csv", "hold.csv"))
    if not os.path.exists(hold):
        everything = os.path.join(W, f"{name}.all.csv")
        r = run([E, "simulate", "--seed", "11", "--sample", f"scattered:{n_all}", "--measure", "positions",
                 "--robot-out", robot, "--out", everything, *options.split()])
        if r.returncode:
            sys.exit(r.stderr)
        lines = [l for l in open(everything) if not l.startswith("#")]
        kind = lines[0].strip().split(",").index("kind")
        targets = [l for l in lines[1:] if l.split(",")[kind] == "target"]
        open(train, "w").write(lines[0] + "".join(targets[:n_train]))
        open(hold, "w").write(lines[0] + "".join(targets[n_train:]))
    return (name, robot, train, hold)


def score(E, W, spec, degree, fits="fits", extra=()):
    name, robot, train, hold = spec
    tag = os.path.join(W, fits, re.sub(r"[^A-Za-z0-9_]", "_", name) + f"_{degree}")
    f = run([E, "fit", "--robot", robot, "--data", train, "--out", tag + ".json", "--joint-functions", str(degree),
             *(extra if degree else ())])
    if f.returncode:
        return {"set": name, "degree": degree, "error": f.stderr.strip()[:200]}
    run([E, "validate", "--model", tag + ".json", "--data", hold, "--summary-out", tag + "_s.json"])
    s = json.load(open(tag + "_s.json"))
    u = s.get("uncertainty", {})
    return {"set": name, "degree": degree, "heldout_rms_mm": s["position"]["after"]["rms_mm"],
            "heldout_max_mm": s["position"]["after"]["max_mm"], "coverage95": u.get("coverage95"),
            "mean_nees": u.get("mean_nees"), "refused": s.get("refused", 0), "error": ""}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("errfield")
    ap.add_argument("workdir")
    ap.add_argument("--degrees", default="0,4,6,8,10,12")
    ap.add_argument("--plan-dirs", default="", help="plan_study.py work directories: their {design}_{n}.csv sets")
    ap.add_argument("--fit-extra", default="", help="more fit options, for every degree but 0")
    ap.add_argument("--fits", default="fits", help="folder of WORKDIR for the fits")
    a = ap.parse_args()
    E, W = a.errfield, a.workdir
    os.makedirs(os.path.join(W, a.fits), exist_ok=True)
    specs = [make_set(E, W, *s) for s in SETS]
    for d in filter(None, a.plan_dirs.split(",")):
        for f in sorted(glob.glob(os.path.join(d, "*_[0-9]*.csv"))):
            b = os.path.basename(f)
            if re.match(r"(random|maximin|adaptive)_\d+\.csv$", b):
                specs.append((os.path.basename(d.rstrip("/")) + "/" + b[:-4], os.path.join(d, "robot.json"), f,
                              os.path.join(d, "hold.csv")))
    degrees = [int(x) for x in a.degrees.split(",")]
    with ThreadPoolExecutor(2) as ex:
        rows = list(ex.map(lambda j: score(E, W, *j, a.fits, a.fit_extra.split()), [(s, d) for s in specs for d in degrees]))
    with open(os.path.join(W, a.fits, "joint_functions.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["set", "degree", "heldout_rms_mm", "heldout_max_mm", "coverage95",
                                          "mean_nees", "refused", "error"])
        w.writeheader()
        w.writerows(rows)
    by = defaultdict(dict)
    for r in rows:
        if not r["error"]:
            by[r["set"]][r["degree"]] = r
    groups = defaultdict(list)
    for name, d in by.items():
        groups[name.split("/")[0]].append(d)
    for g, sets in sorted(groups.items()):
        line = f"{g:10s} {len(sets):3d} sets"
        for k in degrees:
            pairs = [(d[k], d[0]) for d in sets if k in d and 0 in d]
            if not pairs:
                continue
            ratios = [x["heldout_rms_mm"] / y["heldout_rms_mm"] for x, y in pairs]
            gm = math.exp(sum(math.log(r) for r in ratios) / len(ratios))
            cov = sum(x["coverage95"] for x, _ in pairs) / len(pairs)
            line += f" | {k}: x{gm:.3f} (worst x{max(ratios):.3f}) cov {cov:.3f}"
        print(line)


if __name__ == "__main__":
    main()
