#!/usr/bin/python3
"""Several points on the flange (docs/robot.md, "Several points on the flange"): SIMULATED KR 16
poses, each read at three nests r1 = (0,0,100), r2 = (150,0,100), r3 = (0,150,100) mm (flange frame);
the first 240 poses train, the other 200 are held out, 40 training readings locate a point.

usage: scripts/flange_points_study.py ERRFIELD WORKDIR [--seeds 1,2,3] [--robot kr16]
Prints, per seed, the held-out 3-D RMS (mm) and the 95 % radius's coverage of: each point's own
single-point fit; the r1 model with r2 and with r3 located; the r1+r3 model at r3; the r1+r3 model with r2 located; the r1+r2 model with r3
located; the r1+r2+r3 model at each point.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

POINTS = {"r1": (0, 0, 100), "r2": (150, 0, 100), "r3": (0, 150, 100)}
N_POSES, N_TRAIN, N_LOCATE = 440, 240, 40


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(" ".join(cmd) + "\n" + r.stdout + r.stderr)
    return r


def read_split(source, n_train=N_TRAIN):
    """The target rows of a simulated CSV (comments skipped), its columns, and the names of its first
    n_train poses (the training set; the rows of one pose share `point`)."""
    with open(source) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    poses = []
    for r in rows:
        if r["kind"] == "target" and (not poses or poses[-1] != r["point"]):
            poses.append(r["point"])
    return [r for r in rows if r["kind"] == "target"], list(rows[0].keys()), set(poses[:n_train])


def split(source, workdir):
    """Writes train_/test_/locate_ files per label and the label sets the study fits."""
    rows, fields, train = read_split(source)

    def write(name, labels, training, limit=0):
        out = [r for r in rows if r["reflector"] in labels and (r["point"] in train) == training]
        with open(os.path.join(workdir, name), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
            w.writeheader()
            w.writerows(out[:limit] if limit else out)

    for label in POINTS:
        write(f"train_{label}.csv", {label}, True)
        write(f"test_{label}.csv", {label}, False)
        write(f"locate_{label}.csv", {label}, True, N_LOCATE)
    for labels in ("r1r3", "r1r2", "r1r2r3"):
        write(f"train_{labels}.csv", {labels[i:i + 2] for i in range(0, len(labels), 2)}, True)
    write("test_all.csv", set(POINTS), False)


def score(errfield, workdir, model, data, *extra):
    summary = os.path.join(workdir, "summary.json")
    r = subprocess.run([errfield, "validate", "--model", model, "--data", data, *extra, "--summary-out", summary],
                       capture_output=True, text=True)
    if r.returncode != 0:
        return "refused"
    s = json.load(open(summary))
    return f"{s['position']['after']['rms_mm']:.4f} mm, coverage {s['uncertainty']['coverage95']:.3f}"


def study(errfield, workdir, seed, robot_name="kr16"):
    os.makedirs(workdir, exist_ok=True)
    p = lambda name: os.path.join(workdir, name)
    nests = ";".join(",".join(str(v) for v in xyz) for xyz in POINTS.values())
    run([errfield, "simulate", "--robot", robot_name, "--seed", str(seed), "--sample", f"scattered:{N_POSES}",
         "--orientation-spread", "30", "--measure", "positions", "--systematic", "realistic", "--reflectors", nests,
         "--robot-out", p("kr16.json"), "--out", p("readings.csv")])
    robot = json.load(open(p("kr16.json")))
    for label, (x, y, z) in POINTS.items():
        robot["tool"] = {"x_mm": x, "y_mm": y, "z_mm": z, "rx_deg": 0, "ry_deg": 0, "rz_deg": 0}
        json.dump(robot, open(p(f"kr16_{label}.json"), "w"))
    split(p("readings.csv"), workdir)
    print(f"{robot_name} seed {seed} (SIMULATED)")
    for label in POINTS:
        run([errfield, "fit", "--robot", p(f"kr16_{label}.json"), "--data", p(f"train_{label}.csv"), "--out", p(f"m_{label}.json")])
        print(f"  own fit at {label}: {score(errfield, workdir, p(f'm_{label}.json'), p(f'test_{label}.csv'))}")
    for located in ("r2", "r3"):
        moved = p(f"m_r1_{located}.json")
        run([errfield, "locate-tool", "--model", p("m_r1.json"), "--data", p(f"locate_{located}.csv"), "--out", moved])
        print(f"  r1 alone, {located} located: {score(errfield, workdir, moved, p(f'test_{located}.csv'))}")
    for labels, located in (("r1r3", "r2"), ("r1r2", "r3"), ("r1r2r3", None)):
        model = p(f"m_{labels}.json")
        run([errfield, "fit", "--robot", p("kr16_r1.json"), "--data", p(f"train_{labels}.csv"), "--out", model])
        for label in (labels[i:i + 2] for i in range(0, len(labels), 2)):
            if label != "r1":
                print(f"  {labels} at {label}: {score(errfield, workdir, model, p('test_all.csv'), '--reflector', label)}")
        if located:
            moved = p(f"m_{labels}_{located}.json")
            run([errfield, "locate-tool", "--model", model, "--data", p(f"locate_{located}.csv"), "--out", moved])
            print(f"  {labels}, {located} located: {score(errfield, workdir, moved, p(f'test_{located}.csv'))}")
        print(f"  {labels} at r1: {score(errfield, workdir, model, p('test_all.csv'), '--reflector', 'r1')}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("errfield")
    ap.add_argument("workdir")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--robot", default="kr16", help="built-in robot simulate takes (kr16, ur5e, er20-c10, ...)")
    a = ap.parse_args()
    for seed in (int(s) for s in a.seeds.split(",")):
        study(a.errfield, os.path.join(a.workdir, f"{a.robot}_seed{seed}"), seed, a.robot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
