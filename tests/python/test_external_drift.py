"""Kriging with external drift (covariates=) in Python against `errfield interpolate|cv|variogram|
fit-variogram --covariates` on the same simulated data, and against the bordered kriging system and
an OLS fit written here with NumPy."""
import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, same, write_csv

MODEL = "exp(sill=0.3,range=200)+nug(0.01)"


def data(n=60, m=25, seed=9):
    """Simulated: a field whose mean follows a covariate c (a square-root distance to a line)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1000, size=(n, 2))
    t = rng.uniform(0, 1000, size=(m, 2))
    cov = lambda p: np.sqrt(np.abs(p[:, 0] - 400.0) / 100.0)  # noqa: E731
    z = -0.8 * cov(x) + np.sin(x[:, 1] / 150.0) + 0.05 * rng.standard_normal(n)
    return x, z, cov(x), t, cov(t)


def files(tmp_path, x, z, c, t, ct):
    s = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "v": z, "c": c})
    tt = write_csv(tmp_path / "t.csv", {"x": t[:, 0], "y": t[:, 1], "c": ct})
    return s, tt


@pytest.mark.parametrize("extra,cli_extra", [
    ({}, []),
    ({"neighbors": 15}, ["--neighbors", "15"]),
    ({"kind": "universal1"}, ["--kind", "universal1"]),
])
def test_kriging_with_covariates_matches_cli(tmp_path, extra, cli_extra):
    x, z, c, t, ct = data()
    s, tt = files(tmp_path, x, z, c, t, ct)
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "v",
            "--covariates", "c", "--model", MODEL, *cli_extra, "--out", tmp_path / "o.csv")
    csv = read_csv(tmp_path / "o.csv")
    k = errfield.Kriging(x, z, MODEL, covariates=c, covariate_names=["c"], **extra)
    assert k.report["drift_terms"] == (4 if extra.get("kind") == "universal1" else 2)
    mean, var = k.predict(t, covariates=ct)
    assert same(mean, numbers(csv["pred"]))
    assert same(var, numbers(csv["var"]))


def test_kriging_with_covariates_is_the_bordered_system(tmp_path):
    x, z, c, t, ct = data(n=40, m=5)
    model = errfield.VariogramModel(MODEL)
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
    n = len(x)
    a = np.zeros((n + 2, n + 2))
    a[:n, :n] = model.covariance(d)
    a[:n, n] = a[n, :n] = 1.0
    a[:n, n + 1] = a[n + 1, :n] = c
    mean, var = errfield.Kriging(x, z, MODEL, covariates=c[:, None]).predict(t, covariates=ct[:, None])
    for j in range(len(t)):
        b = np.concatenate([model.covariance(np.linalg.norm(x - t[j], axis=1)), [1.0, ct[j]]])
        w = np.linalg.solve(a, b)
        assert mean[j] == pytest.approx(w[:n] @ z, rel=1e-10)
        assert var[j] == pytest.approx(model.covariance(0.0) - w @ b, rel=1e-9)


@pytest.mark.parametrize("folds", ["loo", 4])
def test_cross_validation_with_covariates_matches_cli(tmp_path, folds):
    x, z, c, t, ct = data()
    s, _ = files(tmp_path, x, z, c, t, ct)
    run_cli("cv", "--method", "kriging", "--samples", s, "--coords", "x,y", "--value", "v", "--covariates", "c",
            "--model", MODEL, "--folds", folds, "--out", tmp_path / "cv.csv")
    csv = read_csv(tmp_path / "cv.csv")
    cv = errfield.Kriging(x, z, MODEL, covariates=c).cross_validate(folds=folds)
    assert same(cv.prediction, numbers(csv["pred"]))
    assert same(cv.variance, numbers(csv["var"]))


def test_residual_variogram_matches_cli_and_numpy_ols(tmp_path):
    x, z, c, t, ct = data()
    s, _ = files(tmp_path, x, z, c, t, ct)
    run_cli("variogram", "--input", s, "--coords", "x,y", "--value", "v", "--covariates", "c", "--bins", "0:600:100",
            "--out", tmp_path / "v.csv")
    csv = read_csv(tmp_path / "v.csv")
    edges = np.arange(0.0, 601.0, 100.0)
    v = errfield.variogram(x, z, edges, covariates=c)
    assert np.allclose(v.gamma, numbers(csv["gamma"]), rtol=1e-13, atol=0)
    f = np.column_stack([np.ones_like(c), c])
    resid = z - f @ np.linalg.lstsq(f, z, rcond=None)[0]
    assert np.allclose(v.gamma, errfield.variogram(x, resid, edges).gamma, rtol=1e-10, atol=0)


def test_likelihood_with_covariates_matches_cli(tmp_path):
    x, z, c, t, ct = data()
    s, _ = files(tmp_path, x, z, c, t, ct)
    out = run_cli("fit-variogram", "--method", "reml", "--input", s, "--coords", "x,y", "--value", "v",
                  "--covariates", "c", "--model", "exp")
    r = errfield.fit_likelihood(x, z, "exp", covariates=c)
    assert str(r["model"]) == out.splitlines()[0]
    nll = errfield.negative_log_likelihood(x, z, r["model"], covariates=c)
    assert nll == pytest.approx(r["negative_log_likelihood"], rel=1e-12)
    assert abs(errfield.negative_log_likelihood(x, z, r["model"]) - nll) > 1e-3  # the covariate is in F


def test_covariate_errors_name_what_is_wrong():
    x, z, c, t, ct = data()
    bad = c.copy()
    bad[3] = np.nan
    with pytest.raises(errfield.Error, match="covariates"):
        errfield.Kriging(x, z, MODEL, covariates=bad)
    k = errfield.Kriging(x, z, MODEL, covariates=c, covariate_names=["dist"])
    with pytest.raises(errfield.Error, match="covariates=.*at the targets"):
        k.predict(t)
    with pytest.raises(errfield.Error, match="rows"):
        k.predict(t, covariates=ct[:-1])
    with pytest.raises(errfield.Error, match="covariate 'dist' is constant"):
        errfield.Kriging(x, z, MODEL, covariates=np.full(len(x), 2.0), covariate_names=["dist"])


def test_simulate_with_covariates_matches_cli(tmp_path):
    # Conditional draws with external drift: the CLI's for the same seed, and the drift needs the
    # targets' covariates (refused without them).
    x, z, c, t, ct = data()
    s, tt = files(tmp_path, x, z, c, t, ct)
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "v",
            "--covariates", "c", "--model", MODEL, "--simulations", "2", "--seed", "3", "--out", tmp_path / "o.csv")
    csv = read_csv(tmp_path / "o.csv")
    k = errfield.Kriging(x, z, MODEL, covariates=c, covariate_names=["c"])
    draws = k.simulate(t, 2, seed=3, covariates=ct)
    assert np.array_equal(draws[1], numbers(csv["sim2"]))
    with pytest.raises(errfield.ArgumentError):
        k.simulate(t, 2)
