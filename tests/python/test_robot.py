"""errfield.Robot: FK and IK against `errfield fk` / `errfield ik` CSV on the same joints, Jacobians
against central finite differences of FK, JSON round trips."""
import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, same, write_csv

ROT = ["r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33"]


def joints(n=25, seed=4):
    rng = np.random.default_rng(seed)
    robot = errfield.Robot.builtin()
    lo, hi = robot.q_min, robot.q_max
    # well inside the limits, away from the wrist singularity q5 = 0
    q = rng.uniform(lo * 0.6, hi * 0.6, size=(n, 6))
    q[:, 4] = np.where(np.abs(q[:, 4]) < 15, 30.0, q[:, 4])
    return q


def tooled():
    t = np.eye(4)
    t[:3, 3] = [10.0, -5.0, 120.0]
    return errfield.Robot.builtin("er20_c10").with_tool(t)


def test_fk_matches_cli(tmp_path):
    robot = tooled()
    robot.save(tmp_path / "robot.json")
    q = joints()
    inp = write_csv(tmp_path / "q.csv", {f"q{k + 1}": q[:, k] for k in range(6)})
    for frame in ("tool", "flange"):
        run_cli("fk", "--input", inp, "--robot", tmp_path / "robot.json", "--frame", frame, "--out", tmp_path / "p.csv")
        csv = read_csv(tmp_path / "p.csv")
        t = errfield.Robot.load(tmp_path / "robot.json").fk(q, frame=frame)
        assert t.shape == (len(q), 4, 4)
        for k, c in enumerate("xyz"):
            assert same(t[:, k, 3], numbers(csv[c]))
        for k, c in enumerate(ROT):
            assert same(t[:, k // 3, k % 3], numbers(csv[c]))
    assert same(robot.fk(q[0]), robot.fk(q)[0])
    assert same(robot.position(q), robot.fk(q)[:, :3, 3])


def test_ik_matches_cli_and_reaches_the_targets(tmp_path):
    robot = errfield.Robot.builtin()
    q = joints(n=12, seed=8)
    t = robot.fk(q)
    cols = {"x": t[:, 0, 3], "y": t[:, 1, 3], "z": t[:, 2, 3]}
    cols.update({c: t[:, k // 3, k % 3] for k, c in enumerate(ROT)})
    inp = write_csv(tmp_path / "t.csv", cols)
    run_cli("ik", "--input", inp, "--out", tmp_path / "q.csv")
    csv = read_csv(tmp_path / "q.csv")
    sol = robot.ik(t)
    for k in range(6):
        assert same(sol.q[:, k], numbers(csv[f"q{k + 1}"]))
    assert sol.status == csv["status"]
    assert same(sol.residual_mm, numbers(csv["residual_mm"]))
    assert sol.ok.all()
    np.testing.assert_allclose(robot.fk(sol.q), t, atol=1e-6)
    # seeded from the true joints, IK stays on their branch
    seeded = robot.ik(t, seed=q)
    np.testing.assert_allclose(seeded.q, q, atol=1e-6)
    pos = robot.ik(t[:, :3, 3], position_only=True, seed=q)
    assert pos.ok.all() and np.max(pos.residual_mm) < 1e-6
    far = robot.ik(np.array([1e5, 0.0, 0.0]), position_only=True)
    assert not far.ok[0] and far.status[0] != "converged"


def numeric_jacobian(robot, q, frame, h_deg=1e-4):
    j = np.zeros((6, 6))
    for k in range(6):
        dq = np.zeros(6)
        dq[k] = h_deg
        tp, tm = robot.fk(q + dq, frame=frame), robot.fk(q - dq, frame=frame)
        h_rad = np.radians(2 * h_deg)
        j[:3, k] = (tp[:3, 3] - tm[:3, 3]) / h_rad
        w = tp[:3, :3] @ tm[:3, :3].T  # small rotation from - to +: skew part / angle
        j[3:, k] = np.array([w[2, 1] - w[1, 2], w[0, 2] - w[2, 0], w[1, 0] - w[0, 1]]) / 2 / h_rad
    return j


def test_geometric_jacobian_equals_finite_differences():
    robot = tooled()
    q = joints(n=4, seed=12)
    jac = robot.jacobian(q)
    assert jac.shape == (4, 6, 6)
    for i in range(4):
        # central differences: truncation ~1e-8 mm/rad, rounding ~3e-7 mm/rad at 2000 mm reach
        np.testing.assert_allclose(jac[i], numeric_jacobian(robot, q[i], "tool"), rtol=0, atol=1e-5)
    np.testing.assert_allclose(robot.jacobian(q[0], frame="flange"), numeric_jacobian(robot, q[0], "flange"),
                               rtol=0, atol=1e-5)


def test_identification_jacobian_equals_finite_differences():
    robot = tooled()
    q = joints(n=3, seed=13)
    jac = robot.identification_jacobian(q)
    names = errfield.Robot.parameter_names()
    assert jac.shape == (3, 3, len(names)) and len(names) == 39
    h = 1e-6
    for p in range(39):
        d = np.zeros(39)
        d[p] = h
        plus = robot.apply_parameter_increment(d).position(q)
        minus = robot.apply_parameter_increment(-d).position(q)
        np.testing.assert_allclose(jac[:, :, p], (plus - minus) / (2 * h), rtol=0, atol=1e-5,
                                   err_msg=names[p])


def test_json_round_trip_and_errors(tmp_path):
    robot = tooled()
    again = errfield.Robot.from_json(robot.to_json())
    assert again.name == robot.name
    assert same(again.mdh, robot.mdh) and same(again.tool, robot.tool)
    q = joints(n=5)
    np.testing.assert_allclose(again.fk(q), robot.fk(q), atol=1e-12)
    with pytest.raises(errfield.InputError, match="not valid JSON"):
        errfield.Robot.from_json("{nope")
    with pytest.raises(errfield.InputError):
        errfield.Robot.load(str(tmp_path / "missing.json"))
    with pytest.raises(errfield.ArgumentError, match=r"q: array of shape \(3, 5\) has 5 columns; expected 6"):
        robot.fk(np.zeros((3, 5)))
    bad = q.copy()
    bad[2, 3] = np.nan
    with pytest.raises(errfield.ArgumentError, match=r"q\[2, 3\] is nan"):
        robot.jacobian(bad)
    with pytest.raises(errfield.ArgumentError, match="frame"):
        robot.fk(q, frame="elbow")
    with pytest.raises(errfield.ArgumentError, match="built-in robots"):
        errfield.Robot.builtin("kuka")
    with pytest.raises(errfield.ArgumentError, match="rotation"):
        robot.ik(np.full((4, 4), 2.0))
    with pytest.raises(errfield.ArgumentError, match=r"seed: 2 joint vectors for 5 targets"):
        robot.ik(robot.fk(q), seed=q[:2])
