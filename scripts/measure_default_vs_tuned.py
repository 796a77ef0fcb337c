#!/usr/bin/env python3
"""Is `errfield fit`'s default as good as a hand-tuned setting? Held-out 3-D RMS and max (SIMULATED data).

Protocol (docs/robot.md, "Predictive uncertainty", issue 19's "default within 5 % of the best
hand-tuned setting, max within 1.1x"): the data of scripts/measure_predictive_coverage.py (per seed
s: `errfield simulate --robot R --seed 1000+s --sample scattered:N+200 --systematic realistic
--orientation-spread 30 --joint-decimals 2`, the first N targets train, the other 200 held out).
Each setting below is fitted on the training rows and validated on the held-out rows; RMS and max
of after_mm are taken over the held-out points every setting accepted (a setting that refuses hard
points must not look better for it). "best" is the setting with the smallest RMS; the ratios are
the default's RMS and max over the best's.
Usage: measure_default_vs_tuned.py path/to/errfield [ROBOT] [N] [SEEDS]
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from simulated_session import split_session  # noqa: E402

SETTINGS = {
    "default": [],
    "--outlier-limit 0": ["--outlier-limit", "0"],
    "--kind universal1": ["--kind", "universal1"],
    "--robust igg3": ["--robust", "igg3"],
    "--max-condition 1e4": ["--max-condition", "10000"],
    "--region-margin 0": ["--region-margin", "0"],
    "--method kinematic": ["--method", "kinematic"],
    "kinematic+kriging --space task": ["--method", "kinematic+kriging", "--space", "task"],
    "--method vector-kriging": ["--method", "vector-kriging"],
}


def main():
    errfield = os.path.abspath(sys.argv[1])
    robot = sys.argv[2] if len(sys.argv) > 2 else "kr16"
    n_train = int(sys.argv[3]) if len(sys.argv) > 3 else 300
    seeds = [int(s) for s in (sys.argv[4] if len(sys.argv) > 4 else "1,2,3,4,5").split(",")]
    work = tempfile.mkdtemp(prefix="tuned_")

    def run(*args):
        r = subprocess.run([errfield, *args], cwd=work, capture_output=True, text=True)
        if r.returncode:
            sys.exit(" ".join(args) + "\n" + r.stderr)

    for s in seeds:
        run("simulate", "--robot", robot, "--seed", str(1000 + s), "--sample", f"scattered:{n_train + 200}",
            "--systematic", "realistic", "--orientation-spread", "30", "--joint-decimals", "2",
            "--robot-out", "r.json", "--out", "all.csv")
        split_session(work, n_train)
        errors = {}
        for name, options in SETTINGS.items():
            run("fit", "--robot", "r.json", "--data", "train.csv", *options, "--out", "m.json")
            run("validate", "--model", "m.json", "--robot", "r.json", "--data", "hold.csv", "--out", "points.csv")
            with open(os.path.join(work, "points.csv")) as f:
                rows = csv.DictReader(l for l in f if not l.startswith("#"))
                errors[name] = {r["point"]: float(r["after_mm"]) for r in rows if r["status"] == "ok"}
        common = set.intersection(*(set(e) for e in errors.values()))
        score = {n: (math.sqrt(sum(e[p] ** 2 for p in common) / len(common)), max(e[p] for p in common))
                 for n, e in errors.items()}
        best = min(score, key=lambda n: score[n][0])
        d, b = score["default"], score[best]
        print(f"{robot} seed {s}, {len(common)} common held-out points: default RMS {d[0]:.4f} max {d[1]:.3f} mm; "
              f"best '{best}' RMS {b[0]:.4f} max {b[1]:.3f} mm; default/best RMS {d[0] / b[0]:.3f}, "
              f"max {d[1] / b[1]:.3f}")
        print("   " + "; ".join(f"{n}: {v[0]:.4f}/{v[1]:.3f}" for n, v in score.items()), flush=True)


if __name__ == "__main__":
    main()
