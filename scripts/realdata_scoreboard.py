#!/usr/bin/python3
"""The real-data scoreboard: errfield's pure defaults on every real laser-tracker set of
../shared/realdata (docs/realdata.md), as a new user runs them, in one table.

Each case imports the vendor files with `errfield import-measurements`, splits them (70/30 by a
seeded shuffle, or a given training/test pair), fits with `errfield fit --robot R.json` and no other
option, and scores the held-out rows with `errfield validate`. R.json is the built-in robot
(`errfield robots --show NAME`) with the tool the data set documents as the measured point (the
UR5's SMR 31 mm, the UR10's T-Mac 109 mm along the flange's z axis): what a user writes down. The figures are the held-out 3-D
position error (mean, max, RMS, mm), the share of points within their own 95 % radius (coverage95,
0.95 expected), the orientation error where a 6-DoF probe measured it (mdeg, coverage), and the fit's
wall time (s).

  scoreboard.py --errfield build/errfield [--slice fast|full] [--out table.csv]
                [--check RECORDED.csv] [--update RECORDED.csv] [--realdata DIR] [--keep DIR]

--check fails (exit 1) when a figure of a case it ran is worse than the recorded one: an error
figure by more than 2 % (new > 1.02 x recorded), a coverage farther from 0.95 by more than 0.02.
Fit times are recorded, never checked (they depend on the machine). A case whose data are missing
(no ../shared/realdata) is skipped with a message, and the check passes on the cases that ran; a
check that ran no case at all exits 77, which ctest reports as skipped (never as passed).
--update writes the figures of the cases that ran into RECORDED.csv (other rows kept): do it in the
commit that changes a figure, and say why in its message.

The fast slice (CI, seconds) is the UR5: 1,000 grid poses -> the 20 random test poses. The full slice
adds the 70/30 splits of the UR5 grid and the UR10 series (minutes), and another day: the model of
series C's 70 % registered with `errfield register` on 30 poses of series B (measured on another day,
the tracker moved, the joints elsewhere: outside the field's region) and scored with `validate
--extrapolate` on B's other poses (no variance is claimed there, so no coverage).
"""
import argparse
import csv
import json
import os
import random
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ERROR_FIGURES = ["mean_mm", "max_mm", "rms_mm", "mean_mdeg", "max_mdeg", "rms_mdeg"]
COVERAGE_FIGURES = ["coverage95", "orientation_coverage95"]
COLUMNS = ["case", "train", "test", "refused"] + ERROR_FIGURES[:3] + ["coverage95"] + ERROR_FIGURES[3:] + \
    ["orientation_coverage95", "fit_s"]
ERROR_TOLERANCE = 1.02
COVERAGE_TOLERANCE = 0.02


def run(cmd, log):
    """Runs an errfield command; a failure stops the scoreboard naming the command and its stderr."""
    t0 = time.monotonic()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    dt = time.monotonic() - t0
    log.write("$ " + " ".join(cmd) + f"\n{p.stdout}{p.stderr}(exit {p.returncode}, {dt:.1f} s)\n")
    if p.returncode != 0:
        sys.exit(f"scoreboard: `{' '.join(cmd)}` failed (exit {p.returncode}):\n{p.stderr.strip()}")
    return dt


def read_rows(path):
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    reader = csv.reader(lines)
    header = next(reader)
    return header, [r for r in reader if r]


def write_rows(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


def split_70_30(header, rows, seed, train_path, test_path):
    """70/30 by poses: rows of one `point` stay together (a probe row, several reflectors)."""
    key = header.index("point") if "point" in header else None
    poses = sorted({r[key] for r in rows}) if key is not None else list(range(len(rows)))
    random.Random(seed).shuffle(poses)
    train = set(poses[: int(round(0.7 * len(poses)))])
    pick = (lambda i, r: r[key] in train) if key is not None else (lambda i, r: i in train)
    write_rows(train_path, header, [r for i, r in enumerate(rows) if pick(i, r)])
    write_rows(test_path, header, [r for i, r in enumerate(rows) if not pick(i, r)])


def score(summary):
    pos = (summary.get("position") or {}).get("after") or {}
    unc = summary.get("uncertainty") or {}
    ori = summary.get("orientation") or {}
    ori_after = ori.get("after") or {}
    figures = {
        "test": pos.get("count", ""), "refused": summary.get("refused", ""),
        "mean_mm": pos.get("mean_mm", ""), "max_mm": pos.get("max_mm", ""), "rms_mm": pos.get("rms_mm", ""),
        "coverage95": unc.get("coverage95", ""),
        "mean_mdeg": ori_after.get("mean_mdeg", ""), "max_mdeg": ori_after.get("max_mdeg", ""),
        "rms_mdeg": ori_after.get("rms_mdeg", ""), "orientation_coverage95": ori.get("coverage95", ""),
    }
    # A figure validate could not compute (no pose answered with an orientation) is null there.
    return {k: ("" if v is None else v) for k, v in figures.items()}


class Case:
    def __init__(self, name, robot, tool_z_mm, preset, files, split, slice_):
        self.name, self.robot, self.tool_z_mm, self.preset = name, robot, tool_z_mm, preset
        self.files, self.split, self.slice = files, split, slice_


def cases(realdata):
    ur5 = os.path.join(realdata, "ur5-wam-jacobi", "UR5")
    ur10 = os.path.join(realdata, "ur10-ipa")
    return [
        Case("ur5 grid -> 20 random", "ur5", 31.0, "ur5-jacobi",
             [os.path.join(ur5, "3D_UR5_uncalibrated_grid_cleaned.csv"),
              os.path.join(ur5, "3D_UR5_uncalibrated_random_cleaned.csv")], "given", "fast"),
        Case("ur5 grid 70/30", "ur5", 31.0, "ur5-jacobi",
             [os.path.join(ur5, "3D_UR5_uncalibrated_grid_cleaned.csv")], "70/30", "full"),
        Case("ur10 C 70/30", "ur10", 109.0, "ur10-ipa",
             [os.path.join(ur10, "Series_C", "measurements_random_poses.csv")], "70/30", "full"),
        Case("ur10 B 70/30", "ur10", 109.0, "ur10-ipa",
             [os.path.join(ur10, "Series_B", "measurements_joint_configurations.csv")], "70/30", "full"),
        Case("ur10 C -> B, register 30", "ur10", 109.0, "ur10-ipa",
             [os.path.join(ur10, "Series_C", "measurements_random_poses.csv"),
              os.path.join(ur10, "Series_B", "measurements_joint_configurations.csv")], "register", "full"),
    ]


REGISTRATION_POSES = 30


def split_registration(header, rows, seed, registration_path, test_path):
    """The first REGISTRATION_POSES poses of a seeded shuffle to register on, the others to score."""
    key = header.index("point")
    poses = sorted({r[key] for r in rows})
    random.Random(seed).shuffle(poses)
    first = set(poses[:REGISTRATION_POSES])
    write_rows(registration_path, header, [r for r in rows if r[key] in first])
    write_rows(test_path, header, [r for r in rows if r[key] not in first])


def run_case(c, errfield, work, log):
    if not all(os.path.exists(f) for f in c.files):
        print(f"scoreboard: {c.name}: skipped, data not found ({c.files[0]})")
        return None
    imported = []
    for k, f in enumerate(c.files):
        out = os.path.join(work, f"in{k}.csv")
        run([errfield, "import-measurements", "--preset", c.preset, "--in", f, "--out", out], log)
        imported.append(out)
    train, test = os.path.join(work, "train.csv"), os.path.join(work, "test.csv")
    registration = os.path.join(work, "registration.csv")
    if c.split == "given":
        train, test = imported
    elif c.split == "register":
        header, rows = read_rows(imported[0])
        split_70_30(header, rows, 0, train, os.path.join(work, "unused.csv"))
        header, rows = read_rows(imported[1])
        split_registration(header, rows, 0, registration, test)
    else:
        header, rows = read_rows(imported[0])
        split_70_30(header, rows, 0, train, test)
    robot = os.path.join(work, "robot.json")
    run([errfield, "robots", "--show", c.robot, "--out", robot], log)
    with open(robot) as f:
        description = json.load(f)
    description["tool"] = {"x_mm": 0, "y_mm": 0, "z_mm": c.tool_z_mm, "rx_deg": 0, "ry_deg": 0, "rz_deg": 0}
    with open(robot, "w") as f:
        json.dump(description, f, indent=1)
    model = os.path.join(work, "model.json")
    fit_s = run([errfield, "fit", "--robot", robot, "--data", train, "--out", model], log)
    validate_options = []
    if c.split == "register":
        registered = os.path.join(work, "model_registered.json")
        run([errfield, "register", "--model", model, "--data", registration, "--out", registered], log)
        model, validate_options = registered, ["--extrapolate"]
    summary_path = os.path.join(work, "summary.json")
    run([errfield, "validate", "--model", model, "--data", test, "--out", os.path.join(work, "points.csv"),
         "--summary-out", summary_path] + validate_options, log)
    with open(summary_path) as f:
        figures = score(json.load(f))
    figures["case"], figures["fit_s"] = c.name, round(fit_s, 1)
    figures["train"] = len(read_rows(train)[1])
    return figures


def fmt(v):
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def check(results, recorded_path):
    header, rows = read_rows(recorded_path)
    recorded = {r[header.index("case")]: dict(zip(header, r)) for r in rows}
    problems = []
    for res in results:
        old = recorded.get(res["case"])
        if old is None:
            problems.append(f"{res['case']}: no recorded figures in {recorded_path} (run --update)")
            continue
        for k in ERROR_FIGURES:
            if old.get(k, "") != "" and res.get(k, "") != "":
                if float(res[k]) > ERROR_TOLERANCE * float(old[k]):
                    problems.append(f"{res['case']}: {k} {fmt(res[k])}, recorded {old[k]} (worse by "
                                    f"{100 * (float(res[k]) / float(old[k]) - 1):.1f} %, limit 2 %)")
        for k in COVERAGE_FIGURES:
            if old.get(k, "") != "" and res.get(k, "") != "":
                if abs(float(res[k]) - 0.95) > abs(float(old[k]) - 0.95) + COVERAGE_TOLERANCE:
                    problems.append(f"{res['case']}: {k} {fmt(res[k])}, recorded {old[k]} (farther from 0.95 "
                                    f"by more than {COVERAGE_TOLERANCE})")
    return problems


def update(results, recorded_path):
    rows = {}
    if os.path.exists(recorded_path):
        header, old = read_rows(recorded_path)
        rows = {r[header.index("case")]: dict(zip(header, r)) for r in old}
    for res in results:
        rows[res["case"]] = {k: fmt(res.get(k, "")) for k in COLUMNS}
    with open(recorded_path, "w", newline="") as f:
        f.write("# real-data scoreboard (scripts/realdata_scoreboard.py), pure defaults; docs/realdata.md\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(COLUMNS)
        for r in rows.values():
            w.writerow([r.get(k, "") for k in COLUMNS])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--errfield", required=True)
    ap.add_argument("--slice", choices=["fast", "full"], default="fast")
    ap.add_argument("--realdata", default=os.path.join(os.path.dirname(ROOT), "shared", "realdata"))
    ap.add_argument("--out")
    ap.add_argument("--check")
    ap.add_argument("--update")
    ap.add_argument("--only", help="run only the case of this name")
    ap.add_argument("--keep", help="keep the working files in this directory")
    a = ap.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        base = a.keep or tmp
        os.makedirs(base, exist_ok=True)
        with open(os.path.join(base, "scoreboard.log"), "w") as log:
            for k, c in enumerate(cases(a.realdata)):
                if a.only and c.name != a.only:
                    continue
                if not a.only and a.slice == "fast" and c.slice != "fast":
                    continue
                work = os.path.join(base, f"case{k}")
                os.makedirs(work, exist_ok=True)
                print(f"scoreboard: {c.name} ...", flush=True)
                r = run_case(c, os.path.abspath(a.errfield), work, log)
                if r:
                    results.append(r)
                    print("  " + ", ".join(f"{k} {fmt(r[k])}" for k in COLUMNS[1:] if r.get(k, "") != ""), flush=True)
    if a.out:
        write_rows(a.out, COLUMNS, [[fmt(r.get(k, "")) for k in COLUMNS] for r in results])
    if a.update:
        update(results, a.update)
    if a.check:
        if not results:
            print(f"scoreboard: no case ran (no real data under {a.realdata}): nothing was checked")
            sys.exit(77)
        problems = check(results, a.check)
        for p in problems:
            print("scoreboard: WORSE: " + p)
        print(f"scoreboard: {len(results)} cases checked against {a.check}, {len(problems)} worse")
        sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
