"""errfield.fit / predict / compensate / validate against `errfield fit/predict/compensate/validate` on
the same SIMULATED data (`errfield simulate`): the model JSON byte for byte, every output column bit
for bit, and the validation summary JSON byte for byte."""
import csv
import json
import math

import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, run_cli_status, same, write_csv


def read_measurements(path):
    """A CSV of `errfield simulate` (leading '#' comments: SIMULATED) as a dict of columns: numbers
    as float64 arrays (empty cell = NaN), text columns (point, kind) as str arrays."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    header, body = rows[0], rows[1:]
    cols = {}
    for k, name in enumerate(header):
        cells = [r[k] for r in body]
        try:
            cols[name] = np.array([float(c) if c != "" else math.nan for c in cells])
        except ValueError:
            cols[name] = np.array(cells)
    return cols


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    run_cli("simulate", "--robot-out", d / "robot.json", "--out", d / "grid.csv")
    run_cli("simulate", "--sample", "random:30", "--seed", "7", "--out", d / "hold.csv")
    with open(d / "grid.csv") as f:
        assert "SIMULATED" in f.readline()
    return d


@pytest.mark.parametrize("method", ["distance-idw", "vector-kriging", "kinematic"])
def test_fit_writes_the_cli_model_file(sim, tmp_path, method):
    run_cli("fit", "--robot", sim / "robot.json", "--data", sim / "grid.csv", "--method", method,
            "--out", tmp_path / "cli.json")
    model = errfield.fit(read_measurements(sim / "grid.csv"), robot=str(sim / "robot.json"), method=method)
    model.save(tmp_path / "py.json")
    cli = (tmp_path / "cli.json").read_bytes()
    assert (tmp_path / "py.json").read_bytes() == cli
    assert model.to_json().encode() == cli
    assert model.method == method
    assert model.fit_report["points"] == 125
    if method != "kinematic":  # a calibration has no leave-one-out of a field
        assert model.fit_report["cross_validation"]["samples"] == 125
    # The Robot object and the path give the same model.
    again = errfield.fit(read_measurements(sim / "grid.csv"), robot=errfield.Robot.load(sim / "robot.json"),
                         method=method)
    assert again.to_json() == model.to_json()
    # A loaded model is the same model (its text may differ in the last digit of angles that the
    # robot JSON reader turns into radians and back; test_predict_matches_cli uses a loaded model).
    loaded = errfield.CompensationModel.load(tmp_path / "cli.json")
    assert loaded.method == method and loaded.fit_report is None


@pytest.mark.parametrize("choice", ["none", "loo"])
def test_fit_variance_calibration_is_the_clis(sim, tmp_path, choice):
    # The same model file as `errfield fit --variance-calibration`; "none" writes no calibration,
    # "loo" (here on a given model, which "auto" keeps as given) writes one with the model scaled.
    given = "sph(sill=0.02,range=700)+nug(0.001)"
    run_cli("fit", "--robot", sim / "robot.json", "--data", sim / "grid.csv", "--method", "vector-kriging",
            "--model", given, "--variance-calibration", choice, "--out", tmp_path / "cli.json")
    model = errfield.fit(read_measurements(sim / "grid.csv"), robot=str(sim / "robot.json"), method="vector-kriging",
                         model=given, variance_calibration=choice)
    assert model.to_json().encode() == (tmp_path / "cli.json").read_bytes()
    field = json.loads(model.to_json())["field"]
    assert ("variance_calibration" in field) == (choice == "loo")
    with pytest.raises(errfield.ArgumentError, match="--variance-calibration"):
        errfield.fit(read_measurements(sim / "grid.csv"), robot=str(sim / "robot.json"), variance_calibration="yes")


@pytest.mark.parametrize("degree", [0, 4])
def test_fit_joint_functions_are_the_clis(sim, tmp_path, degree):
    # kinematic+kriging with per-joint error functions of a degree (0 = none): the CLI's model file.
    run_cli("fit", "--robot", sim / "robot.json", "--data", sim / "grid.csv", "--method", "kinematic+kriging",
            "--joint-functions", degree, "--out", tmp_path / "cli.json")
    model = errfield.fit(read_measurements(sim / "grid.csv"), robot=str(sim / "robot.json"),
                         method="kinematic+kriging", joint_functions=degree)
    assert model.to_json().encode() == (tmp_path / "cli.json").read_bytes()
    stored = json.loads(model.to_json())
    assert ("joint_error_functions" in stored) == (degree > 0)
    if degree:
        assert stored["joint_error_functions"]["degree"] == degree
    with pytest.raises(errfield.ArgumentError, match="joint function degree"):
        errfield.fit(read_measurements(sim / "grid.csv"), robot=str(sim / "robot.json"), joint_functions=21)


@pytest.mark.parametrize("gravity", [True, False])
def test_fit_gravity_load_is_the_clis(sim, tmp_path, gravity):
    # The gravity-load terms beside the joint functions (on by default): the CLI's model file.
    run_cli("fit", "--robot", sim / "robot.json", "--data", sim / "grid.csv", "--method", "kinematic+kriging",
            "--gravity-load", "on" if gravity else "off", "--out", tmp_path / "cli.json")
    model = errfield.fit(read_measurements(sim / "grid.csv"), robot=str(sim / "robot.json"),
                         method="kinematic+kriging", gravity_load=gravity)
    assert model.to_json().encode() == (tmp_path / "cli.json").read_bytes()
    functions = json.loads(model.to_json())["joint_error_functions"]
    assert ("gravity_terms" in functions) == gravity


def check_columns(result, csv_path):
    """Every column the binding returns equals the CLI's column of that name (numbers bit for bit)."""
    csv_ = read_csv(csv_path)
    added = [n for n in csv_ if n in result]
    assert set(result) == set(added), (sorted(result), list(csv_))
    for name, values in result.items():
        if values.dtype.kind == "U":
            assert list(values) == csv_[name], name
        else:
            assert same(values, numbers(csv_[name])), name


@pytest.fixture(scope="module")
def fitted(sim):
    run_cli("fit", "--robot", sim / "robot.json", "--data", sim / "grid.csv", "--method", "vector-kriging",
            "--out", sim / "vk.json")
    return errfield.CompensationModel.load(sim / "vk.json")


def test_predict_matches_cli(sim, fitted, tmp_path):
    run_cli("predict", "--model", sim / "vk.json", "--joints", sim / "hold.csv", "--out", tmp_path / "p.csv")
    data = read_measurements(sim / "hold.csv")
    from_dict = errfield.predict(fitted, data)
    check_columns(from_dict, tmp_path / "p.csv")
    assert set(from_dict) == {"px", "py", "pz", "tx", "ty", "tz", "var_mm2", "var_field_mm2", "r95_mm", "status"}
    q = np.column_stack([data[f"q{j}"] for j in range(1, 7)])
    from_array = errfield.predict(fitted, q)
    for name in from_dict:
        assert np.array_equal(from_array[name], from_dict[name]), name
    # Columns that are strided views of one (N, 6) array (a regression: they were read as if
    # contiguous) give the same predictions.
    strided = {f"q{k + 1}": q[:, k] for k in range(6)}
    assert not strided["q1"].flags.c_contiguous
    from_strided = errfield.predict(fitted, strided)
    for name in from_dict:
        assert np.array_equal(from_strided[name], from_dict[name]), name
    one = errfield.predict(fitted, q[3])
    assert same(one["px"], from_dict["px"][3:4])


def test_predict_on_no_rows_gives_empty_float_columns(fitted):
    """Issue 20: on 0 rows the position columns came back as string arrays."""
    r = errfield.predict(fitted, np.zeros((0, 6)))
    assert {"px", "py", "pz", "status"} <= set(r)
    for name in set(r) - {"status"}:
        assert r[name].dtype == np.float64 and r[name].shape == (0,), name
    assert r["status"].dtype.kind == "U" and r["status"].shape == (0,)


def test_compensate_matches_cli(sim, fitted, tmp_path):
    run_cli("compensate", "--model", sim / "vk.json", "--targets", sim / "hold.csv", "--tolerance", "0.3",
            "--out", tmp_path / "c.csv")
    data = read_measurements(sim / "hold.csv")
    out = errfield.compensate(fitted, data, tolerance=0.3)
    check_columns(out, tmp_path / "c.csv")
    assert (out["status"] == "ok").sum() > 20
    # Pose targets (x,y,z,rx,ry,rz): solved on the training branch, as the CLI does. The simulated
    # targets are tool-down (orientation 180,0,0, simulate's default).
    n = len(data["x"])
    poses = {"x": data["x"], "y": data["y"], "z": data["z"], "rx": np.full(n, 180.0), "ry": np.zeros(n),
             "rz": np.zeros(n)}
    write_csv(tmp_path / "poses.csv", poses)
    run_cli("compensate", "--model", sim / "vk.json", "--robot", sim / "robot.json", "--targets",
            tmp_path / "poses.csv", "--out", tmp_path / "cp.csv")
    by_pose = errfield.compensate(fitted, poses, robot=str(sim / "robot.json"))
    check_columns(by_pose, tmp_path / "cp.csv")
    assert (by_pose["status"] == "ok").sum() > 20


def test_compensate_seeds_and_ceiling_match_cli(sim, fitted, tmp_path):
    # Pose targets with per-row seeds sq1..sq6 (a row without a seed left empty: NaN in Python) and a
    # ceiling on the move: the same columns as the CLI's, and the ceiling refuses what exceeds it.
    data = read_measurements(sim / "hold.csv")
    n = len(data["x"])
    poses = {"x": data["x"], "y": data["y"], "z": data["z"], "rx": np.full(n, 180.0), "ry": np.zeros(n),
             "rz": np.zeros(n)}
    for k in range(1, 7):
        seed = data[f"q{k}"].copy()
        seed[::3] = math.nan  # every third row: no seed of its own
        poses[f"sq{k}"] = seed
    write_csv(tmp_path / "poses.csv", poses)
    default = errfield.compensate(fitted, poses, robot=str(sim / "robot.json"))
    assert (default["status"] == "ok").sum() > 10
    # A ceiling at the median move of the default run: about half the rows refused for it.
    ceiling = float(np.median(default["move_mm"][default["status"] == "ok"]))
    for given in (0.0, ceiling):
        run_cli("compensate", "--model", sim / "vk.json", "--robot", sim / "robot.json", "--targets",
                tmp_path / "poses.csv", "--max-correction", repr(given), "--out", tmp_path / "c.csv")
        out = errfield.compensate(fitted, poses, robot=str(sim / "robot.json"), max_correction=given)
        check_columns(out, tmp_path / "c.csv")
        if given:
            ok = out["status"] == "ok"
            assert ok.sum() > 0 and (out["move_mm"][ok] <= ceiling).all()
            assert (out["status"] == "correction-too-large").sum() > 0
    with pytest.raises(errfield.ArgumentError, match="max_correction"):
        errfield.compensate(fitted, poses, robot=str(sim / "robot.json"), max_correction=-1.0)


def test_compensate_tracker_frame_matches_cli(sim, fitted, tmp_path):
    # frame="tracker" (the CLI's --frame tracker): the held-out readings mx,my,mz as targets, tool down
    # in the robot frame turned into the tracker frame; the same columns as the CLI's, and the same
    # joints as robot-frame targets mapped here with the model file's registration.
    data = read_measurements(sim / "hold.csv")
    reg = np.array(json.loads((sim / "vk.json").read_text())["registration"]["robot_from_tracker"])
    rot, shift = reg[:, :3], reg[:, 3]
    down = np.diag([1.0, -1.0, -1.0])  # rx 180, ry 0, rz 0
    r_t = rot.T @ down  # R = Rz Ry Rx: ry = asin(-r31), rx = atan2(r32, r33), rz = atan2(r21, r11)
    angles = np.degrees([math.atan2(r_t[2, 1], r_t[2, 2]), math.asin(-r_t[2, 0]), math.atan2(r_t[1, 0], r_t[0, 0])])
    n = len(data["mx"])
    tracker = {"x": data["mx"], "y": data["my"], "z": data["mz"]}
    tracker.update({k: np.full(n, a) for k, a in zip(("rx", "ry", "rz"), angles)})
    write_csv(tmp_path / "tracker.csv", tracker)
    run_cli("compensate", "--model", sim / "vk.json", "--targets", tmp_path / "tracker.csv", "--frame", "tracker",
            "--out", tmp_path / "ct.csv")
    out = errfield.compensate(fitted, tracker, frame="tracker")
    check_columns(out, tmp_path / "ct.csv")
    ok = out["status"] == "ok"
    assert ok.sum() > 20
    p = np.column_stack([data["mx"], data["my"], data["mz"]]) @ rot.T + shift
    robot = {"x": p[:, 0], "y": p[:, 1], "z": p[:, 2], "rx": np.full(n, 180.0), "ry": np.zeros(n), "rz": np.zeros(n)}
    by_robot = errfield.compensate(fitted, robot)
    assert (by_robot["status"] == out["status"]).all()
    for name in [f"cq{k}" for k in range(1, 7)] + ["nx", "ny", "nz"]:
        assert np.allclose(out[name][ok], by_robot[name][ok], rtol=0, atol=1e-9), name
    with pytest.raises(errfield.ArgumentError, match="frame"):
        errfield.compensate(fitted, tracker, frame="world")
    with pytest.raises(errfield.ArgumentError, match="no frame"):
        errfield.compensate(fitted, np.column_stack([data[f"q{k}"] for k in range(1, 7)]), frame="tracker")


def test_validate_matches_cli(sim, fitted, tmp_path):
    run_cli("validate", "--model", sim / "vk.json", "--robot", sim / "robot.json", "--data", sim / "hold.csv",
            "--out", tmp_path / "v.csv", "--summary-out", tmp_path / "s.json")
    r = errfield.validate(fitted, read_measurements(sim / "hold.csv"), robot=str(sim / "robot.json"))
    check_columns(r["points"], tmp_path / "v.csv")
    assert r["summary_json"].encode() == (tmp_path / "s.json").read_bytes()
    assert r["summary"] == json.loads((tmp_path / "s.json").read_text())
    # Compensation helps on simulated data with a smooth error field: RMS after < before.
    pos = r["summary"]["position"]
    assert pos["after"]["rms_mm"] < pos["before"]["rms_mm"]


def test_validate_matches_cli_with_the_reflector_off_the_robot_json_tool(tmp_path):
    """A calibrated model whose reflector fit located ~20 mm from the robot JSON's tool (as on the real
    UR10: the T-Mac point at 93 mm, the JSON's tool at 109): the binding's 'before' is the nominal
    robot at that reflector, as the CLI's. It was at the JSON's tool: 15.9 mm on the UR10 where the
    CLI says 1.01. SIMULATED KR 16 poses, tool unknown to the robot JSON (tests/compensation/
    register_cli_test.cpp's set-up)."""
    run_cli("simulate", "--robot", "kr16", "--seed", "7", "--sample", "scattered:120", "--joint-box",
            "-30,30,-80,-40,10,50,-40,40,40,80,-40,40", "--tool-offset", "random:20", "--joint-decimals", "3",
            "--measure", "positions", "--robot-out", tmp_path / "kr16.json", "--out", tmp_path / "all.csv")
    lines = [line for line in (tmp_path / "all.csv").read_text().splitlines() if not line.startswith("#")]
    kind = lines[0].split(",").index("kind")
    rows = [line for line in lines[1:] if line.split(",")[kind] == "target"]
    (tmp_path / "train.csv").write_text("\n".join([lines[0], *rows[:90]]) + "\n")
    (tmp_path / "hold.csv").write_text("\n".join([lines[0], *rows[90:]]) + "\n")
    run_cli("fit", "--robot", tmp_path / "kr16.json", "--data", tmp_path / "train.csv", "--out", tmp_path / "m.json")
    model_file = json.loads((tmp_path / "m.json").read_text())
    assert np.linalg.norm(model_file["reflector_mm"]) > 10.0  # the premise: the reflector is not the JSON's tool (0)
    run_cli("validate", "--model", tmp_path / "m.json", "--data", tmp_path / "hold.csv", "--out", tmp_path / "v.csv",
            "--summary-out", tmp_path / "s.json")
    model = errfield.CompensationModel.load(tmp_path / "m.json")
    r = errfield.validate(model, read_measurements(tmp_path / "hold.csv"))
    cli = json.loads((tmp_path / "s.json").read_text())
    assert r["summary"]["position"]["before"] == cli["position"]["before"]
    assert r["summary"] == cli
    assert cli["position"]["before"]["rms_mm"] < 5.0


def test_pipeline_errors(sim, fitted):
    data = read_measurements(sim / "grid.csv")
    with pytest.raises(errfield.ArgumentError, match="--robust: expected 'none' or 'igg3'"):
        errfield.fit(data, robot=str(sim / "robot.json"), method="kinematic", robust="huber")
    with pytest.raises(errfield.ArgumentError, match=r"data\['q1'\]: 3 rows but 'point' has 126"):
        errfield.fit({**data, "q1": np.zeros(3)})
    with pytest.raises(errfield.ArgumentError, match="data: expected a dict of columns"):
        errfield.fit(np.zeros((4, 6)))
    with pytest.raises(errfield.ArgumentError, match="tolerance"):
        errfield.compensate(fitted, np.zeros((1, 6)), tolerance=0.0)
    with pytest.raises(errfield.ArgumentError, match="joints"):
        errfield.predict(fitted, np.zeros((2, 5)))
    # Without the robot that has the measured tool, the CLI and the binding refuse alike.
    status, _, err = run_cli_status("fit", "--data", sim / "grid.csv", "--out", sim / "never.json")
    with pytest.raises(errfield.InputError) as e:
        errfield.fit(data)
    assert status == 2 and str(e.value).split(": ", 1)[1][:60] in err


def test_plan_matches_cli(tmp_path):
    # A SIMULATED KR16 pool; the first 40 rows measured: the same choice as `errfield plan`, with and
    # without the model fitted on them, and the same predicted RMS.
    run_cli("simulate", "--robot", "kr16", "--seed", "5", "--sample", "scattered:160", "--joint-box",
            "-60,60,-100,-40,20,110,-90,90,30,100,-90,90", "--measure", "positions", "--out", tmp_path / "all.csv")
    data = read_measurements(tmp_path / "all.csv")
    targets = {k: v[1:] for k, v in data.items()}
    measured = {k: v[:40] for k, v in targets.items()}
    pool = {k: v[40:] for k, v in targets.items()}
    write_csv(tmp_path / "measured.csv", {k: v for k, v in measured.items() if k not in ("point", "kind")})
    # point columns for the CLI's matching by name
    with open(tmp_path / "pool.csv", "w") as f:
        names = ["point"] + [f"q{k}" for k in range(1, 7)]
        f.write(",".join(names) + "\n")
        for i in range(len(pool["q1"])):
            f.write(",".join([pool["point"][i]] + [repr(float(pool[f"q{k}"][i])) for k in range(1, 7)]) + "\n")
    run_cli("plan", "--robot", "kr16", "--candidates", tmp_path / "pool.csv", "--count", "12",
            "--data", tmp_path / "measured.csv", "--out", tmp_path / "n.csv")
    first = errfield.plan(pool, count=12, measured=measured)
    assert list(read_csv(tmp_path / "n.csv")["point"]) == [pool["point"][i] for i in first["chosen"]]
    assert first["poses_for_target"] is None and len(first["predicted_rms_mm"]) == 0
    model = errfield.fit(measured, robot="kr16")
    model.save(tmp_path / "m.json")
    run_cli("plan", "--candidates", tmp_path / "pool.csv", "--count", "12", "--model", tmp_path / "m.json",
            "--data", tmp_path / "measured.csv", "--target-rms", "0.01", "--summary-out", tmp_path / "s.json",
            "--out", tmp_path / "n2.csv")
    # The model as the CLI reads it: the file's robot angles are converted to radians and back, so an
    # in-memory model may differ in the last bit of its command model, which the joint error
    # functions' Jacobians (in the prediction) see.
    loaded = errfield.CompensationModel.load(tmp_path / "m.json")
    second = errfield.plan(pool, count=12, model=loaded, measured=measured, target_rms=0.01)
    assert list(read_csv(tmp_path / "n2.csv")["point"]) == [pool["point"][i] for i in second["chosen"]]
    s = json.loads((tmp_path / "s.json").read_text())
    assert second["predicted_rms_mm"][0] == s["predicted_rms_mm"]["now"]
    assert list(second["predicted_rms_mm"]) == s["predicted_rms_mm"]["by_pose"]
    # The prediction's 90 % range and the advice's (issue 35): the CLI's numbers.
    assert [second["predicted_rms_low_mm"][0], second["predicted_rms_high_mm"][0]] == s["predicted_rms_mm"]["now_range"]
    assert second["predicted_mse_relative_se"] == s["predicted_rms_mm"]["mse_relative_se"]
    assert list(second["poses_for_target_range"]) == s["poses_for_target_range"]
    # The spacing floor: the CLI's option, the same choice; 0 is variance reduction alone.
    run_cli("plan", "--candidates", tmp_path / "pool.csv", "--count", "12", "--model", tmp_path / "m.json",
            "--data", tmp_path / "measured.csv", "--spacing-floor", "0", "--out", tmp_path / "n3.csv")
    free = errfield.plan(pool, count=12, model=loaded, measured=measured, spacing_floor=0.0)
    assert list(read_csv(tmp_path / "n3.csv")["point"]) == [pool["point"][i] for i in free["chosen"]]
    assert "at least 0.7" in second["design"] and "at least" not in free["design"]
    with pytest.raises(errfield.ArgumentError, match="count"):
        errfield.plan(pool, count=0)
    # Issue 35: more poses than the pool has were clamped in silence; a repeated pose counts once.
    n = len(pool["q1"])
    with pytest.raises(errfield.ArgumentError, match=f"count: {n + 1} poses asked, but {n} of the {n}"):
        errfield.plan(pool, count=n + 1)
    twice = {k: np.concatenate([v, v[:3]]) for k, v in pool.items() if k.startswith("q")}
    with pytest.raises(errfield.ArgumentError, match="3 repeat an earlier candidate"):
        errfield.plan(twice, count=n + 1)
    assert sorted(errfield.plan(twice, count=n)["chosen"]) == list(range(n))
    with pytest.raises(errfield.ArgumentError, match="spacing_floor"):
        errfield.plan(pool, count=5, model=loaded, measured=measured, spacing_floor=1.0)


def test_locate_tool_and_tool_match_cli(sim, tmp_path):
    """Issue 34: errfield.locate_tool writes the CLI's model byte for byte and reports its figures
    (the readings' kriged residual at the point among them); predict at the located point is the
    CLI's; readings at one orientation and a tool 3 m away are refused. SIMULATED KR 16 poses within 30 deg of tool-down (a model
    fitted at one orientation refuses readings at others as outside its region)."""
    common = ["--robot", "kr16", "--seed", "4", "--orientation-spread", "30", "--measure", "positions",
              "--systematic", "realistic"]
    run_cli("simulate", *common, "--sample", "scattered:120", "--robot-out", tmp_path / "kr16.json",
            "--out", tmp_path / "a.csv")
    run_cli("simulate", *common, "--sample", "scattered:120", "--tool-offset", "100,0,0", "--out", tmp_path / "b.csv")
    run_cli("fit", "--robot", tmp_path / "kr16.json", "--data", tmp_path / "a.csv", "--out", tmp_path / "m.json")
    lines = [line for line in (tmp_path / "b.csv").read_text().splitlines() if not line.startswith("#")]
    kind = lines[0].split(",").index("kind")
    rows = [line for line in lines[1:] if line.split(",")[kind] == "target"][:40]
    (tmp_path / "b40.csv").write_text("\n".join([lines[0], *rows]) + "\n")
    out = run_cli("locate-tool", "--model", tmp_path / "m.json", "--data", tmp_path / "b40.csv",
                  "--out", tmp_path / "cli.json")
    fitted = errfield.CompensationModel.load(tmp_path / "m.json")
    model, report = errfield.locate_tool(fitted, read_measurements(tmp_path / "b40.csv"))
    model.save(tmp_path / "py.json")
    cli = json.loads((tmp_path / "cli.json").read_text())
    py = json.loads((tmp_path / "py.json").read_text())
    cli.pop("notes", None)  # the CLI's note names its file
    py.pop("notes", None)
    assert py == cli
    t = cli["working_tool"]
    assert np.allclose(report["tool_mm"], [t.get("x_mm", 0), t.get("y_mm", 0), t.get("z_mm", 0)], atol=1e-12)
    assert report["readings"] == 40 and report["orientations"] >= 3
    assert "fit residual RMS" in out and report["residual_rms_mm"] >= 0
    assert all(s > 0 for s in report["sd_mm"])
    c = report["correction"]
    assert c is not None and c["readings"] == 40
    assert np.allclose(np.square(c["sd_mm"]), cli["tool_point_correction"]["sill_mm2"], rtol=1e-12, atol=0)
    assert c["variance_factor"] == cli["tool_point_correction"]["variance_factor"]
    assert f"{c['uncorrected_rms_mm']:.4f}".rstrip("0") in out
    # predict at the located point (its correction included): the same columns as the CLI's
    a = read_csv(tmp_path / "b40.csv")
    write_csv(tmp_path / "q.csv", {f"q{k}": numbers(a[f"q{k}"]) for k in range(1, 7)})  # joints only
    run_cli("predict", "--model", tmp_path / "cli.json", "--joints", tmp_path / "q.csv", "--out", tmp_path / "p.csv")
    # (from the saved file, as the CLI reads it: the working tool's rotation goes through degrees in
    # the file, which moves a prediction by 1e-13 mm)
    reloaded = errfield.CompensationModel.load(tmp_path / "py.json")
    check_columns(errfield.predict(reloaded, read_measurements(tmp_path / "q.csv")), tmp_path / "p.csv")
    with pytest.raises(errfield.InputError, match="distinct flange orientation"):
        errfield.locate_tool(fitted, read_measurements(sim / "grid.csv"))
    with pytest.raises(errfield.ArgumentError, match="tool"):
        errfield.predict(fitted, read_measurements(tmp_path / "q.csv"), tool=[3000.0, 0.0, 0.0])


def test_joints_in_radians_are_refused_as_by_the_cli(tmp_path):
    """Issue 35: the CLI refuses joints that look like radians against the model's training joints;
    the module took them (every row ok). A SIMULATED UR5e, as the CLI's test."""
    box = "-90,90,-120,-40,40,120,-120,-40,40,120,-90,90"
    run_cli("simulate", "--robot", "ur5e", "--seed", "41", "--sample", "scattered:40", "--joint-box", box,
            "--measure", "positions", "--robot-out", tmp_path / "r.json", "--out", tmp_path / "train.csv")
    run_cli("fit", "--robot", tmp_path / "r.json", "--data", tmp_path / "train.csv", "--method", "kinematic",
            "--out", tmp_path / "k.json")
    run_cli("simulate", "--robot", "ur5e", "--seed", "42", "--sample", "scattered:12", "--joint-box", box,
            "--measure", "positions", "--out", tmp_path / "held.csv")
    held = read_measurements(tmp_path / "held.csv")
    q_deg = np.column_stack([held[f"q{j}"] for j in range(1, 7)])
    q_rad = np.radians(q_deg)
    model = errfield.CompensationModel.load(tmp_path / "k.json")
    with pytest.raises(errfield.InputError, match="radians.*joints_are_degrees=True"):
        errfield.predict(model, q_rad)
    with pytest.raises(errfield.InputError, match="radians.*joints_are_degrees=True"):
        errfield.compensate(model, q_rad)
    # degrees go through; the override takes the radians as degrees, as the CLI's flag does
    # (the base point's row, q1 = 209 deg, q2 = -212 deg, lies far outside the training poses: the
    # calibration cannot vouch for it)
    status = errfield.predict(model, q_deg)["status"]
    assert (status[held["kind"] == "target"] == "ok").all()
    assert (status[held["kind"] == "base"] == "calibration-extrapolated").all()
    assert len(errfield.compensate(model, q_deg)["status"]) == len(q_deg)
    assert len(errfield.predict(model, q_rad, joints_are_degrees=True)["status"]) == len(q_rad)
    assert len(errfield.compensate(model, q_rad, joints_are_degrees=True)["status"]) == len(q_rad)


def test_probe_readings_fit_and_validate_as_the_cli(tmp_path):
    # A SIMULATED 6-DoF probe: its rows are three points on the flange in the module as in the CLI,
    # and validate reports the flange's orientation (the same summary, byte for byte).
    run_cli("simulate", "--robot", "kr16", "--seed", "2", "--sample", "scattered:160", "--orientation-spread", "30",
            "--measure", "positions", "--systematic", "realistic", "--probe", "0,0,100,180,0,0",
            "--robot-out", tmp_path / "kr16.json", "--out", tmp_path / "probe.csv")
    robot = json.loads((tmp_path / "kr16.json").read_text())
    robot["tool"] = {"x_mm": 0, "y_mm": 0, "z_mm": 100, "rx_deg": 0, "ry_deg": 0, "rz_deg": 0}
    (tmp_path / "tool.json").write_text(json.dumps(robot))
    lines = [line for line in (tmp_path / "probe.csv").read_text().splitlines() if not line.startswith("#")]
    (tmp_path / "train.csv").write_text("\n".join(lines[:101]) + "\n")  # the header, b0 and 99 poses
    (tmp_path / "test.csv").write_text("\n".join(lines[:1] + lines[101:]) + "\n")
    train, test = read_measurements(tmp_path / "train.csv"), read_measurements(tmp_path / "test.csv")
    run_cli("fit", "--robot", tmp_path / "tool.json", "--data", tmp_path / "train.csv", "--out", tmp_path / "cli.json")
    model = errfield.fit(train, robot=str(tmp_path / "tool.json"))
    assert model.to_json().encode() == (tmp_path / "cli.json").read_bytes()
    run_cli("validate", "--model", tmp_path / "cli.json", "--data", tmp_path / "test.csv",
            "--summary-out", tmp_path / "s.json")
    # The loaded model (an in-memory one differs in the last digits, test_fit_writes_the_cli_model_file).
    r = errfield.validate(errfield.CompensationModel.load(tmp_path / "cli.json"), test)
    assert r["summary_json"].encode() == (tmp_path / "s.json").read_bytes()
    o = r["summary"]["orientation"]
    assert o["poses"] == len(test["point"])
    assert o["after"]["rms_mdeg"] < 0.5 * o["before"]["rms_mdeg"]
    assert "flange orientation error" in r["text"]
