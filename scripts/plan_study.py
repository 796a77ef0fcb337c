#!/usr/bin/python3
"""Measurement-plan study (issue 21): held-out 3-D RMS against the number of measured poses for
random, maximin (space-filling) and adaptive (`errfield plan --model`) selection, with the RMS
`plan` predicted beside the one achieved. Data SIMULATED by `errfield simulate`, or real
measurements with --measurements (the real-data scoreboard's imported CSVs).

usage: scripts/plan_study.py ERRFIELD_BINARY WORKDIR [--robot kr16] [--seed 3] [--pool 2000]
       [--holdout 300] [--batch 40] [--batches 6] [--long-counts 320,480,687]
       [--extra "simulate options"] [--target-rms MM]
Prints one table row per (design, count); writes WORKDIR/plan_study.csv. --long-counts scores random
and maximin also at these larger counts (the whole pool at most): how many poses each needs for
what adaptive reaches with fewer. With --target-rms, each adaptive row also records what the model
fitted so far advises for that target (poses in total: central, and the 90 % range's ends) and the
prediction's 90 % range: whether the advice moves between batches by more than its own range.
"""
import argparse
import csv
import json
import os
import random
import subprocess
import sys


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr}")
    return r


def read(path):
    with open(path, newline="") as f:
        lines = [l for l in f if not l.startswith("#")]
    rows = list(csv.reader(lines))
    return rows[0], rows[1:]


def write(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("errfield")
    ap.add_argument("workdir")
    ap.add_argument("--robot", default="kr16")
    ap.add_argument("--seed", default="3")
    ap.add_argument("--pool", type=int, default=2000)
    ap.add_argument("--holdout", type=int, default=300)
    ap.add_argument("--batch", type=int, default=40)
    ap.add_argument("--batches", type=int, default=6)
    ap.add_argument("--designs", default="random,maximin,adaptive")
    ap.add_argument("--local-scale", default="on")
    ap.add_argument("--long-counts", default="")
    ap.add_argument("--maximin-batches", type=int, default=1,
                    help="adaptive: how many first batches are maximin (model-free) before plan --model")
    ap.add_argument("--target-rms", default="", help="adaptive: ask plan for this target's advice at every batch")
    ap.add_argument("--measurements", default="",
                    help="real data instead of simulate: a measurement CSV (point,q1..q6,mx,my,mz, e.g. from "
                         "import-measurements), shuffled with --seed, its first --pool rows the pool and the "
                         "next --holdout held out; needs --robot-file")
    ap.add_argument("--robot-file", default="", help="with --measurements: the robot JSON (its tool included)")
    ap.add_argument("--plan-extra", default="", help="more options for plan --model, e.g. \"--spacing-floor 0.5\"")
    ap.add_argument("--extra", default="--joint-box -150,150,-130,-30,70,150,-90,90,-110,110,-180,180 "
                                        "--systematic realistic --orientation-spread 30 --joint-decimals 3")
    a = ap.parse_args()
    E, W = a.errfield, a.workdir
    os.makedirs(W, exist_ok=True)
    robot = os.path.join(W, "robot.json")
    allcsv = os.path.join(W, "all.csv")
    if a.measurements:
        if not a.robot_file:
            sys.exit("--measurements needs --robot-file")
        robot = a.robot_file
        header, rows = read(a.measurements)
        # Shuffled by pose (a pose read at several flange points keeps all its rows together).
        pt = header.index("point")
        order = list(dict.fromkeys(r[pt] for r in rows))
        random.Random(int(a.seed)).shuffle(order)
        rank = {p: k for k, p in enumerate(order[: a.pool + a.holdout])}
        write(allcsv, header, sorted((r for r in rows if r[pt] in rank), key=lambda r: rank[r[pt]]))
    elif not os.path.exists(allcsv):
        run([E, "simulate", "--robot", a.robot, "--seed", a.seed, "--sample", f"scattered:{a.pool + a.holdout}",
             *a.extra.split(), "--measure", "positions", "--robot-out", robot, "--out", allcsv])
    header, rows = read(allcsv)
    targets = [r for r in rows if r[header.index("kind")] == "target"] if "kind" in header else rows
    # A pose read at several points on the flange (column 'reflector') has one row per point: the
    # pool and the held-out set are counted in poses, each with all its rows.
    point = header.index("point")
    poses = list(dict.fromkeys(r[point] for r in targets))
    in_pool = set(poses[: a.pool])
    pool = [r for r in targets if r[point] in in_pool]
    hold = [r for r in targets if r[point] not in in_pool and r[point] in set(poses[a.pool: a.pool + a.holdout])]
    write(os.path.join(W, "pool.csv"), header, pool)
    write(os.path.join(W, "hold.csv"), header, hold)
    by_point = {}
    for r in pool:
        by_point.setdefault(r[point], []).append(r)
    out_rows = []

    def score(tag, chosen, predicted=None, predicted_by_own=None):
        data = os.path.join(W, f"{tag}.csv")
        write(data, header, [r for p in chosen for r in by_point[p]])
        model = os.path.join(W, f"{tag}.json")
        run([E, "fit", "--robot", robot, "--data", data, "--out", model])
        s = os.path.join(W, f"{tag}_s.json")
        run([E, "validate", "--model", model, "--data", os.path.join(W, "hold.csv"), "--summary-out", s])
        summary = json.load(open(s))
        rms = summary["position"]["after"]["rms_mm"]
        row = {"design": tag.split("_")[0], "poses": len(chosen), "heldout_rms_mm": rms,
               "heldout_max_mm": summary["position"]["after"]["max_mm"],
               "refused": summary.get("refused", 0), "predicted_before_mm": predicted,
               "predicted_by_own_model_mm": predicted_by_own}
        out_rows.append(row)
        print(f"{row['design']:9s} {row['poses']:4d}  held-out RMS {rms:.4f} mm  max {row['heldout_max_mm']:.3f}"
              f"  refused {row['refused']}" + (f"  predicted before {predicted:.4f} mm" if predicted else ""), flush=True)
        return model, row

    designs = a.designs.split(",")
    counts = [a.batch * (k + 1) for k in range(a.batches)]
    long_counts = sorted(set(counts) | {min(int(c), len(pool)) for c in a.long_counts.split(",") if c})
    if "random" in designs:
        order = list(dict.fromkeys(r[point] for r in pool))
        random.Random(int(a.seed)).shuffle(order)
        for n in long_counts:
            score(f"random_{n}", order[:n])
    if "maximin" in designs:
        nxt = os.path.join(W, "maximin_order.csv")
        run([E, "plan", "--robot", robot, "--candidates", os.path.join(W, "pool.csv"), "--count",
             str(long_counts[-1]), "--out", nxt])
        order = list(dict.fromkeys(r[point] for r in read(nxt)[1]))
        for n in long_counts:
            score(f"maximin_{n}", order[:n])
    if "adaptive" in designs:
        chosen = []
        model, predicted = None, None
        for n in counts:
            nxt = os.path.join(W, f"adaptive_next_{n}.csv")
            cmd = [E, "plan", "--robot", robot, "--candidates", os.path.join(W, "pool.csv"), "--count", str(a.batch),
                   "--out", nxt]
            if model and n > a.batch * a.maximin_batches:
                summ = os.path.join(W, f"adaptive_plan_{n}.json")
                cmd += ["--model", model, "--data", os.path.join(W, f"adaptive_{n - a.batch}.csv"),
                        "--summary-out", summ, "--local-scale", a.local_scale, *a.plan_extra.split()]
            if n <= a.batch * a.maximin_batches and chosen:
                cmd += ["--data", os.path.join(W, f"adaptive_{n - a.batch}.csv")]
            run(cmd)
            if model and n > a.batch * a.maximin_batches:
                predicted = json.load(open(summ))["predicted_rms_mm"]["after"]
            chosen += list(dict.fromkeys(r[point] for r in read(nxt)[1]))
            model, row = score(f"adaptive_{n}", chosen, predicted)
            # What the model fitted on these poses predicts for itself (plan's "now").
            own = os.path.join(W, f"adaptive_own_{n}.json")
            run([E, "plan", "--robot", robot, "--candidates", os.path.join(W, "pool.csv"), "--count", "1",
                 "--model", model, "--data", os.path.join(W, f"adaptive_{n}.csv"), "--summary-out", own,
                 "--local-scale", a.local_scale, *(["--target-rms", a.target_rms] if a.target_rms else []),
                 "--out", os.path.join(W, "own_next.csv")])
            own_summary = json.load(open(own))
            pr = own_summary["predicted_rms_mm"]
            row["predicted_by_own_model_mm"] = pr["now"]
            row["predicted_low_mm"], row["predicted_high_mm"] = pr.get("now_range", [None, None])
            line = (f"          predicted by its own model {pr['now']:.4f} mm"
                    + (f" (90 % range {row['predicted_low_mm']:.4f}-{row['predicted_high_mm']:.4f})"
                       if row["predicted_low_mm"] is not None else "")
                    + f", ratio to held-out {pr['now'] / row['heldout_rms_mm']:.3f}")
            if a.target_rms:
                total = lambda k: None if k is None else n + k
                rng = own_summary.get("poses_for_target_range", [None, None])
                row["advice_total"] = total(own_summary.get("poses_for_target"))
                row["advice_total_low"], row["advice_total_high"] = total(rng[0]), total(rng[1])
                line += (f"; target {a.target_rms}: {row['advice_total']} poses in total"
                         f" (range {row['advice_total_low']} to {row['advice_total_high']})")
            print(line, flush=True)
    with open(os.path.join(W, "plan_study.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in out_rows for k in r)))
        w.writeheader()
        w.writerows(out_rows)


if __name__ == "__main__":
    main()
