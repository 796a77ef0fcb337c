"""errfield.calibrate_distances against `errfield calibrate --model distance` on the same SIMULATED
data: the identified robot JSON byte for byte, with base rows (robot positions) and with fixed base
points, and a recovery check against the simulator's true robot."""
import json

import numpy as np
import pytest

import errfield
from conftest import run_cli
from test_pipeline import read_measurements

FIXED = [(600.0, -600.0, 0.0), (1400.0, 600.0, 0.0), (600.0, 600.0, 1200.0)]


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    run_cli("simulate", "--robot-out", d / "robot.json", "--truth-out", d / "truth.json", "--out", d / "grid.csv")
    fixed = [a for b in FIXED for a in ("--fixed-base", ",".join(map(str, b)))]
    run_cli("simulate", "--robot-out", d / "robot_f.json", *fixed, "--out", d / "fixed.csv")
    return d


def test_base_rows_match_cli(sim, tmp_path):
    run_cli("calibrate", "--robot", sim / "robot.json", "--model", "distance", "--data", sim / "grid.csv",
            "--out", tmp_path / "cli.json")
    data = read_measurements(sim / "grid.csv")
    r = errfield.calibrate_distances(str(sim / "robot.json"), data)
    assert (r["robot"].to_json() + "\n").encode() == (tmp_path / "cli.json").read_bytes()
    assert r["converged"] and r["rms_after_mm"] < 0.2 * r["rms_before_mm"]
    assert r["fixed_bases"].shape == (0, 3)
    assert r["regularization"] > 0  # distances: regularized toward nominal (docs/robot.md)
    # Distances are frame-free: the identified robot's distances between targets match the truth's
    # far better than the nominal robot's (SIMULATED truth from --truth-out).
    truth = errfield.Robot.load(sim / "truth.json")
    nominal = errfield.Robot.load(sim / "robot.json")
    q = np.column_stack([data[f"q{k}"] for k in range(1, 7)])

    def pair_distances(robot):
        p = robot.position(q)
        return np.linalg.norm(p[1:] - p[:-1], axis=1)

    err_after = np.abs(pair_distances(r["robot"]) - pair_distances(truth)).max()
    err_before = np.abs(pair_distances(nominal) - pair_distances(truth)).max()
    assert err_after < 0.25 * err_before


def test_fixed_base_points_match_cli(sim, tmp_path):
    points = [a for b in FIXED for a in ("--base-point", ",".join(map(str, b)))]
    run_cli("calibrate", "--robot", sim / "robot_f.json", "--model", "distance", "--data", sim / "fixed.csv",
            *points, "--out", tmp_path / "cli.json")
    r = errfield.calibrate_distances(errfield.Robot.load(sim / "robot_f.json"), read_measurements(sim / "fixed.csv"),
                                     base_points=np.array(FIXED))
    assert (r["robot"].to_json() + "\n").encode() == (tmp_path / "cli.json").read_bytes()
    assert r["fixed_bases"].shape == (3, 3)
    # identified near their nominal positions (the simulator moves them by at most a few mm)
    assert np.abs(r["fixed_bases"] - np.array(FIXED)).max() < 20.0


def test_errors(sim):
    data = read_measurements(sim / "grid.csv")
    with pytest.raises(errfield.ArgumentError, match="data:2 is a base row"):
        errfield.calibrate_distances(str(sim / "robot.json"), data, base_points=[FIXED[0]])
    targets = data["kind"] == "target"
    no_kind = {k: v[targets] for k, v in data.items() if k != "kind"}
    with pytest.raises(errfield.InputError, match="needs a 'kind' column"):
        errfield.calibrate_distances(str(sim / "robot.json"), no_kind)
    bad = dict(data)
    bad["dist_b0"] = data["dist_b0"].copy()
    bad["dist_b0"][5] = -3.0
    with pytest.raises(errfield.InputError, match="dist_b0"):
        errfield.calibrate_distances(str(sim / "robot.json"), bad)
