"""errfield.Cokriging against `errfield interpolate|cv --method kriging --model lmc.json` on the same
data, and simple cokriging against the Gaussian-process posterior written here with NumPy."""
import json

import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, run_cli_status, same, write_csv

LMC = {"type": "lmc", "components": ["a", "b"],
       "structures": [{"kind": "nug", "sills": [[0.02, 0.005], [0.005, 0.03]]},
                      {"kind": "sph", "range": 400, "sills": [[0.5, 0.3], [0.3, 0.4]]},
                      {"kind": "exp", "range": 100, "sills": [[0.1, -0.05], [-0.05, 0.2]]}]}


def data(n=40, m=25, seed=3):
    # SIMULATED: smooth functions plus noise, not a draw of the model.
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1000, size=(n, 2))
    a = np.sin(x[:, 0] / 200.0) + 0.05 * rng.standard_normal(n)
    b = 0.5 * a + np.cos(x[:, 1] / 300.0)
    t = rng.uniform(-50, 1050, size=(m, 2))
    return x, np.column_stack([a, b]), t


def lmc_covariance(h):
    """P x P covariance blocks C(h) of LMC for an array of lags (h > 0), written out here."""
    c = np.zeros(h.shape + (2, 2))
    for s in LMC["structures"]:
        b = np.array(s["sills"])
        if s["kind"] == "nug":
            unit = (h == 0).astype(float)
        elif s["kind"] == "sph":
            r = np.minimum(h / s["range"], 1.0)
            unit = 1.0 - (1.5 * r - 0.5 * r ** 3)
        else:
            unit = np.exp(-h / s["range"])
        c += unit[..., None, None] * b
    return c


@pytest.mark.parametrize("extra,cli_extra", [
    ({}, []),
    ({"kind": "universal1", "neighbors": 15}, ["--kind", "universal1", "--neighbors", "15"]),
    ({"kind": "simple", "mean": [0.1, 0.2]}, ["--kind", "simple", "--mean", "0.1"]),
])
def test_cokriging_matches_cli(tmp_path, extra, cli_extra):
    x, z, t = data()
    if extra.get("kind") == "simple":
        extra = dict(extra, mean=0.1)  # the CLI's --mean takes one value for all components
    s = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "a": z[:, 0], "b": z[:, 1]})
    tt = write_csv(tmp_path / "t.csv", {"x": t[:, 0], "y": t[:, 1]})
    (tmp_path / "lmc.json").write_text(json.dumps(LMC))
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "a,b",
            "--model", tmp_path / "lmc.json", *cli_extra, "--out", tmp_path / "o.csv")
    csv = read_csv(tmp_path / "o.csv")
    mean, var, cov = errfield.Cokriging(x, z, LMC, **extra).predict(t)
    assert mean.shape == (len(t), 2) and var.shape == (len(t), 2) and cov.shape == (len(t), 2, 2)
    assert same(mean[:, 0], numbers(csv["pred_a"])) and same(mean[:, 1], numbers(csv["pred_b"]))
    assert same(var[:, 0], numbers(csv["var_a"])) and same(var[:, 1], numbers(csv["var_b"]))
    assert same(cov[:, 0, 1], numbers(csv["cov_a_b"])) and same(cov[:, 1, 0], cov[:, 0, 1])
    assert same(np.diagonal(cov, axis1=1, axis2=2), var)


def test_cross_validation_matches_cli(tmp_path):
    x, z, _ = data()
    s = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "a": z[:, 0], "b": z[:, 1]})
    (tmp_path / "lmc.json").write_text(json.dumps(LMC))
    run_cli("cv", "--method", "kriging", "--samples", s, "--coords", "x,y", "--value", "a,b",
            "--model", tmp_path / "lmc.json", "--out", tmp_path / "cv.csv")
    csv = read_csv(tmp_path / "cv.csv")
    pred, residual, cov = errfield.Cokriging(x, z, json.dumps(LMC)).cross_validate()
    assert same(pred[:, 1], numbers(csv["pred_b"]))
    np.testing.assert_allclose(residual, z - pred, rtol=0, atol=1e-14)
    assert same(cov[:, 0, 0], numbers(csv["var_a"])) and same(cov[:, 0, 1], numbers(csv["cov_a_b"]))


def test_simple_cokriging_is_the_gaussian_process_posterior():
    x, z, t = data(n=30, m=10)
    mu = np.array([0.1, -0.2])
    mean, _, cov = errfield.Cokriging(x, z, LMC, kind="simple", mean=list(mu)).predict(t)
    n, p = len(x), 2
    # Joint covariance of all components at all samples, sample-major; C(0) = the total sill.
    k = lmc_covariance(np.linalg.norm(x[:, None] - x[None], axis=2)).transpose(0, 2, 1, 3).reshape(n * p, n * p)
    ks = lmc_covariance(np.linalg.norm(t[:, None] - x[None], axis=2)).transpose(0, 2, 1, 3).reshape(len(t) * p, n * p)
    alpha = np.linalg.solve(k, (z - mu).reshape(-1))
    gp_mean = mu + (ks @ alpha).reshape(len(t), p)
    sill = sum(np.array(s["sills"]) for s in LMC["structures"])
    gp_cov = np.array([sill - ks[i * p:(i + 1) * p] @ np.linalg.solve(k, ks[i * p:(i + 1) * p].T) for i in range(len(t))])
    np.testing.assert_allclose(mean, gp_mean, rtol=0, atol=1e-10)
    np.testing.assert_allclose(cov, gp_cov, rtol=0, atol=1e-10)


def test_refuses_a_model_of_another_component_count_and_bad_json():
    x, z, _ = data()
    with pytest.raises(errfield.ArgumentError, match="values: 1 columns but the model has 2 components"):
        errfield.Cokriging(x, z[:, :1], LMC)
    with pytest.raises(errfield.ArgumentError, match="not valid JSON"):
        errfield.Cokriging(x, z, "{not json")
    with pytest.raises(errfield.ArgumentError, match="sparse back end"):
        errfield.Cokriging(x, z, LMC, backend="sparse")


def test_nan_is_a_component_not_measured_there(tmp_path):
    # Heterotopic: b measured at about 60 % of the samples. Simple cokriging is then the Gaussian-process
    # posterior of the observations that exist (the joint covariance without the rows of the NaNs), and
    # the CLI with empty cells gives the same numbers as the binding with NaN.
    x, z, t = data(n=30, m=10, seed=5)
    rng = np.random.default_rng(6)
    z[rng.uniform(size=len(x)) < 0.4, 1] = np.nan
    assert np.isnan(z[:, 1]).sum() >= 5
    mu = np.array([0.1, -0.2])
    mean, _, cov = errfield.Cokriging(x, z, LMC, kind="simple", mean=list(mu)).predict(t)
    n, p = len(x), 2
    keep = ~np.isnan(z.reshape(-1))  # sample-major rows that exist
    k = lmc_covariance(np.linalg.norm(x[:, None] - x[None], axis=2)).transpose(0, 2, 1, 3).reshape(n * p, n * p)
    ks = lmc_covariance(np.linalg.norm(t[:, None] - x[None], axis=2)).transpose(0, 2, 1, 3).reshape(len(t) * p, n * p)
    k, ks = k[np.ix_(keep, keep)], ks[:, keep]
    alpha = np.linalg.solve(k, (z - mu).reshape(-1)[keep])
    gp_mean = mu + (ks @ alpha).reshape(len(t), p)
    sill = sum(np.array(s["sills"]) for s in LMC["structures"])
    gp_cov = np.array([sill - ks[i * p:(i + 1) * p] @ np.linalg.solve(k, ks[i * p:(i + 1) * p].T) for i in range(len(t))])
    np.testing.assert_allclose(mean, gp_mean, rtol=0, atol=1e-10)
    np.testing.assert_allclose(cov, gp_cov, rtol=0, atol=1e-10)

    s = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "a": z[:, 0], "b": z[:, 1]})
    tt = write_csv(tmp_path / "t.csv", {"x": t[:, 0], "y": t[:, 1]})
    (tmp_path / "lmc.json").write_text(json.dumps(LMC))
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "a,b",
            "--model", tmp_path / "lmc.json", "--out", tmp_path / "o.csv")
    csv = read_csv(tmp_path / "o.csv")
    mean, var, _ = errfield.Cokriging(x, z, LMC).predict(t)
    assert np.isfinite(mean).all()
    assert same(mean[:, 1], numbers(csv["pred_b"])) and same(var[:, 1], numbers(csv["var_b"]))
    # A row with nothing measured, or an infinity, is still refused.
    z[3] = np.nan
    with pytest.raises(errfield.InputError, match="sample 3 has no measured component"):
        errfield.Cokriging(x, z, LMC)
    z[3] = [1.0, np.inf]
    with pytest.raises(errfield.InputError, match="expected a finite number"):
        errfield.Cokriging(x, z, LMC)
