#!/usr/bin/python3
"""`interpolate --model auto --auto-search fast` against `thorough`, held out (issue 49).

For each data set: a 70/30 split (seed 0; jura: gstat's own prediction / validation sets), the model
chosen on the 70 % by each search, kriged onto the 30 %: wall time of the whole command, held-out
RMSE, mean z^2 (residual^2 / kriging variance: ~1 when the variance is right) and the chosen model.
The gstat data sets are exported from R's gstat package at run time (nothing of them is kept in
the project); the two 1,000-sample sets are SIMULATED here (numpy, fixed seeds).

  /usr/bin/python3 scripts/auto_search_study.py --errfield build/errfield [--keep DIR]

Needs Rscript with gstat and sp (Debian r-cran-gstat) and numpy (python3-numpy).
"""
import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

R_EXPORT = r"""
library(gstat); library(sp)
out <- commandArgs(TRUE)[1]
data(meuse); meuse$logzinc <- log(meuse$zinc)
write.csv(meuse[, c("x", "y", "logzinc")], file.path(out, "meuse.csv"), row.names = FALSE)
data(coalash); write.csv(coalash, file.path(out, "coalash.csv"), row.names = FALSE)
data(oxford); write.csv(oxford[, c("XCOORD", "YCOORD", "MG1", "PH1")], file.path(out, "oxford.csv"), row.names = FALSE)
data(fulmar)
f98 <- fulmar[fulmar$year == 1998, c("x", "y", "fulmar")]
f98$ind5 <- as.numeric(f98$fulmar < 5)
write.csv(f98, file.path(out, "fulmar98.csv"), row.names = FALSE)
write.csv(fulmar[fulmar$year == 1999, c("x", "y", "fulmar")], file.path(out, "fulmar99.csv"), row.names = FALSE)
data(jura)
write.csv(jura.pred[, c("Xloc", "Yloc", "Ni", "Cd")], file.path(out, "jura_train.csv"), row.names = FALSE)
write.csv(jura.val[, c("Xloc", "Yloc", "Ni", "Cd")], file.path(out, "jura_test.csv"), row.names = FALSE)
"""

# name, file, x, y, value (jura: its own split)
SETS = [
    ("meuse log(zinc)", "meuse.csv", "x", "y", "logzinc"),
    ("coalash", "coalash.csv", "x", "y", "coalash"),
    ("oxford MG1", "oxford.csv", "XCOORD", "YCOORD", "MG1"),
    ("oxford PH1", "oxford.csv", "XCOORD", "YCOORD", "PH1"),
    ("jura Ni", "jura", "Xloc", "Yloc", "Ni"),
    ("jura Cd", "jura", "Xloc", "Yloc", "Cd"),
    ("fulmar 1998", "fulmar98.csv", "x", "y", "fulmar"),
    ("fulmar 1998 I(<5)", "fulmar98.csv", "x", "y", "ind5"),
    ("fulmar 1999", "fulmar99.csv", "x", "y", "fulmar"),
    ("SIMULATED exp 1,430", "sim_exp.csv", "x", "y", "z"),
    ("SIMULATED gau 1,430", "sim_gau.csv", "x", "y", "z"),
]


def simulate(path, kind, seed):
    """1,430 points in [0, 1000]^2 (1,000 for training after the split), unit sill, range 150 / 200."""
    rng = np.random.default_rng(seed)
    n = 1430
    x = rng.uniform(0, 1000, (n, 2))
    d = np.sqrt(((x[:, None, :] - x[None, :, :]) ** 2).sum(-1))
    if kind == "exp":
        k = np.exp(-d / 150.0) + 0.1 * np.eye(n)
    else:
        k = np.exp(-(d / 200.0) ** 2) + 0.05 * np.eye(n)
    z = np.linalg.cholesky(k) @ rng.standard_normal(n)
    with open(path, "w") as f:
        f.write("x,y,z\n")
        for (a, b), v in zip(x, z):
            f.write(f"{a:.6f},{b:.6f},{v:.8f}\n")


def split(path, train, test, seed=0):
    rows = list(csv.DictReader(open(path)))
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(rows))
    cut = int(round(0.7 * len(rows)))
    for name, idx in ((train, order[:cut]), (test, order[cut:])):
        with open(name, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            for i in sorted(idx):
                w.writerow(rows[i])


def run(errfield, train, test, xc, yc, value, search, out):
    cmd = [errfield, "interpolate", "--method", "kriging", "--samples", train, "--targets", test, "--coords",
           f"{xc},{yc}", "--value", value, "--model", "auto", "--auto-search", search, "--out", out]
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr}")
    model = ""
    for line in p.stderr.splitlines():
        if "--model auto: " in line and "chosen by" in line:
            model = line.split("--model auto: ", 1)[1].split(", chosen by")[0]
    rows = list(csv.DictReader(open(out)))
    truth = np.array([float(r[value]) for r in rows])
    pred = np.array([float(r["pred"]) for r in rows])
    var = np.array([float(r["var"]) for r in rows])
    res = truth - pred
    return wall, float(np.sqrt(np.mean(res ** 2))), float(np.mean(res ** 2 / var)), model


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--errfield", default="build/errfield")
    ap.add_argument("--keep", help="directory to keep the data and outputs in")
    a = ap.parse_args()
    errfield = os.path.abspath(a.errfield)
    work = a.keep or tempfile.mkdtemp(prefix="auto_search_")
    os.makedirs(work, exist_ok=True)
    subprocess.run(["Rscript", "-e", R_EXPORT, work], check=True, capture_output=True)
    simulate(os.path.join(work, "sim_exp.csv"), "exp", 3)
    simulate(os.path.join(work, "sim_gau.csv"), "gau", 4)
    print("| data (training / held-out samples) | search | time s | held-out RMSE | mean z^2 | model chosen |")
    print("|---|---|---|---|---|---|")
    for name, file, xc, yc, value in SETS:
        if file == "jura":
            train, test = os.path.join(work, "jura_train.csv"), os.path.join(work, "jura_test.csv")
        else:
            stem = os.path.join(work, os.path.splitext(file)[0])
            train, test = stem + "_train.csv", stem + "_test.csv"
            split(os.path.join(work, file), train, test)
        sizes = f"{sum(1 for _ in open(train)) - 1} / {sum(1 for _ in open(test)) - 1}"
        for search in ("fast", "thorough"):
            out = os.path.join(work, f"{name.replace(' ', '_').replace('(', '').replace(')', '').replace('<', 'lt').replace(',', '')}_{search}.csv")
            wall, rmse, z2, model = run(errfield, train, test, xc, yc, value, search, out)
            print(f"| {name} ({sizes}) | {search} | {wall:.2f} | {rmse:.5g} | {z2:.3f} | `{model}` |", flush=True)


if __name__ == "__main__":
    main()
