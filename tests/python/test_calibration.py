"""errfield.calibrate_positions against `errfield calibrate --model position` on the same data, and
its recovery of a known perturbed robot from exact positions."""
import json

import numpy as np

import errfield
from conftest import run_cli, write_csv


def scenario(n=40, noise=0.0, seed=21):
    rng = np.random.default_rng(seed)
    nominal = errfield.Robot.builtin()
    names = errfield.Robot.parameter_names()
    delta = np.zeros(len(names))
    for name, value in {"link2.a": 0.5, "link3.a": -0.4, "link4.d": 0.3, "link3.alpha": 1e-3,
                        "link2.theta0": 2e-3, "tool.z": 0.8}.items():
        delta[names.index(name)] = value  # mm, rad
    true_robot = nominal.apply_parameter_increment(delta)
    c, s = np.cos(0.3), np.sin(0.3)
    tracker = np.array([[c, -s, 0, 2500.0], [s, c, 0, -400.0], [0, 0, 1, -120.0], [0, 0, 0, 1]])
    q = rng.uniform(0.6 * nominal.q_min, 0.6 * nominal.q_max, size=(n, 6))
    p = true_robot.position(q)
    measured = p @ tracker[:3, :3].T + tracker[:3, 3] + noise * rng.standard_normal((n, 3))
    return nominal, q, measured, tracker


def test_matches_cli(tmp_path):
    nominal, q, measured, _ = scenario(noise=0.02)
    cols = {f"q{k + 1}": q[:, k] for k in range(6)}
    cols.update({"mx": measured[:, 0], "my": measured[:, 1], "mz": measured[:, 2]})
    data = write_csv(tmp_path / "m.csv", cols)
    run_cli("calibrate", "--model", "position", "--data", data, "--out", tmp_path / "r.json")
    r = errfield.calibrate_positions(nominal, q, measured)
    # The CLI's robot JSON also stores the tracker registration (for validate/predict/fk); the
    # robot description itself must be the same, number for number.
    cli = json.loads((tmp_path / "r.json").read_text())
    cli.pop("registration", None)
    assert json.loads(r["robot"].to_json()) == cli
    assert r["converged"] and r["rms_after_mm"] < r["rms_before_mm"]
    assert len(r["weights"]) == len(q)


def test_recovers_a_perturbed_robot_from_exact_positions():
    nominal, q, measured, tracker = scenario()
    r = errfield.calibrate_positions(nominal, q, measured, robust=False)
    assert r["converged"], r["message"]
    t = r["tracker_from_base"]
    predicted = r["robot"].position(q) @ t[:3, :3].T + t[:3, 3]
    # exact data: the identified model reproduces every measurement (nominal misses by ~1 mm)
    assert np.max(np.linalg.norm(predicted - measured, axis=1)) < 1e-5
    assert r["rms_before_mm"] > 0.1
    others = errfield.Robot.builtin().with_base(tracker)
    assert np.max(np.linalg.norm(others.position(q) - measured, axis=1)) > 0.1


def test_errors():
    nominal, q, measured, _ = scenario(n=10)
    import pytest
    with pytest.raises(errfield.ArgumentError, match="measured: 9 positions for 10 joint vectors"):
        errfield.calibrate_positions(nominal, q, measured[:9])
    bad = q.copy()
    bad[3, 1] = 500.0
    with pytest.raises(errfield.ArgumentError, match=r"q\[3, 1\]: 500.* outside the joint limits"):
        errfield.calibrate_positions(nominal, bad, measured)
