#!/usr/bin/env python3
"""Does the predictive variance hold? coverage95 and mean NEES of every kriging method (SIMULATED data).

Protocol (docs/robot.md, "Predictive uncertainty"): for each seed s, `errfield simulate --robot R
--seed 1000+s --sample scattered:N+200 --systematic realistic --orientation-spread 30
--joint-decimals 2` (data that look real); the base row and the first N targets are the training
set, the other 200 targets the hold-out (one session: both share the base point's reading). Each
method is fitted with its defaults (plus EXTRA fit options) and scored with `errfield validate`:
coverage95 and mean_nees from the summary; for distance-kriging, which has no 3-D variance, the share
of distance errors (after_dl_b0) within 1.96 sqrt(var_mm2) and the mean z^2 (1 expected). Prints
per seed and pooled over the seeds, with the pooled binomial standard error sqrt(0.95 * 0.05 / n).
Usage: measure_predictive_coverage.py path/to/errfield [ROBOT] [N] [SEEDS] [EXTRA] [SYSTEMATIC]
  e.g. measure_predictive_coverage.py build/errfield kr16 300 1,2,3,4,5 "--variance-calibration none"
  SYSTEMATIC is simulate's --systematic (default realistic; config = the default simulation's effects)
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from simulated_session import split_session  # noqa: E402

METHODS = [("auto", []), ("kinematic+kriging task", ["--method", "kinematic+kriging", "--space", "task"]),
           ("vector-kriging joint", ["--method", "vector-kriging"]),
           ("vector-kriging task", ["--method", "vector-kriging", "--space", "task"]),
           ("distance-kriging joint", ["--method", "distance-kriging"]),
           ("distance-kriging task", ["--method", "distance-kriging", "--space", "task"])]


def main():
    errfield = os.path.abspath(sys.argv[1])
    robot = sys.argv[2] if len(sys.argv) > 2 else "kr16"
    n_train = int(sys.argv[3]) if len(sys.argv) > 3 else 300
    seeds = [int(s) for s in (sys.argv[4] if len(sys.argv) > 4 else "1,2,3,4,5").split(",")]
    extra = sys.argv[5].split() if len(sys.argv) > 5 else []
    systematic = sys.argv[6] if len(sys.argv) > 6 else "realistic"
    work = tempfile.mkdtemp(prefix="coverage_")

    def run(*args):
        r = subprocess.run([errfield, *args], cwd=work, capture_output=True, text=True)
        if r.returncode:
            sys.exit(" ".join(args) + "\n" + r.stderr)

    pooled = {}
    for s in seeds:
        run("simulate", "--robot", robot, "--seed", str(1000 + s), "--sample", f"scattered:{n_train + 200}",
            "--systematic", systematic, "--orientation-spread", "30", "--joint-decimals", "2",
            "--robot-out", "r.json", "--out", "all.csv")
        split_session(work, n_train)
        for name, options in METHODS:
            run("fit", "--robot", "r.json", "--data", "train.csv", *options, *extra, "--out", "m.json")
            run("validate", "--model", "m.json", "--robot", "r.json", "--data", "hold.csv", "--summary-out", "s.json",
                "--out", "points.csv")
            summary = json.load(open(os.path.join(work, "s.json")))
            if name.startswith("distance"):
                with open(os.path.join(work, "points.csv")) as f:
                    rows = [r for r in csv.DictReader(l for l in f if not l.startswith("#")) if r["status"] == "ok"]
                z2 = [float(r["after_dl_b0"]) ** 2 / float(r["var_mm2"]) for r in rows]
                n = len(z2)
                coverage, nees = sum(z <= 1.959964 ** 2 for z in z2) / n, sum(z2) / n
                scores = summary["distance"]["after"]
            else:
                u = summary["uncertainty"]
                coverage, nees, n = u["coverage95"], u["mean_nees"], u["points"]
                scores = summary["position"]["after"]
            pooled.setdefault(name, []).append((coverage, nees, n, scores["rms_mm"], scores["max_mm"]))
            print(f"{robot} seed {s} {name:24s} coverage95 {coverage:.3f} mean NEES {nees:.2f} on {n}, "
                  f"RMS {scores['rms_mm']:.4f} mm, max {scores['max_mm']:.3f} mm", flush=True)
    print(f"pooled over seeds {seeds} ({robot}, {n_train} training poses, SIMULATED):")
    for name, v in pooled.items():
        n = sum(x[2] for x in v)
        coverage = sum(x[0] * x[2] for x in v) / n
        nees = sum(x[1] * x[2] for x in v) / n
        print(f"  {name:24s} coverage95 {coverage:.3f} (binomial SE {math.sqrt(0.95 * 0.05 / n):.3f}, {n} points) "
              f"mean NEES {nees:.2f}, mean RMS {sum(x[3] for x in v) / len(v):.4f} mm, "
              f"mean max {sum(x[4] for x in v) / len(v):.3f} mm; per seed " + " ".join(f"{x[0]:.2f}" for x in v))


if __name__ == "__main__":
    main()
