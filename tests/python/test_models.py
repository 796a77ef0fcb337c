"""Variogram models: text syntax, evaluation against the closed forms, WLS and ML/REML fits
against `errfield fit-variogram`, and the likelihood against a NumPy implementation of its formula."""
import math

import numpy as np
import pytest
from scipy.special import gamma as gamma_fn
from scipy.special import kv

import errfield
from conftest import read_csv, run_cli, write_csv


def test_text_round_trip_and_properties():
    m = errfield.VariogramModel("sph(sill=0.3,range=400)+nug(0.002)")
    assert str(m) == "sph(sill=0.3,range=400)+nug(sill=0.002)"
    assert errfield.VariogramModel.parse(str(m)) == m
    assert m.sill == pytest.approx(0.302) and m.nugget == 0.002
    assert m.bounded and m.compact and m.support == 400
    assert m.components == [{"kind": "sph", "sill": 0.3, "range": 400.0}, {"kind": "nug", "sill": 0.002}]
    assert not errfield.VariogramModel("pow(sill=1,exponent=1.5)").bounded


def test_gamma_equals_closed_forms():
    h = np.array([0.0, 1e-3, 10.0, 99.0, 100.0, 150.0, 1000.0])
    s, a = 2.5, 100.0
    r = h / a
    expected = {
        "sph": np.where(h < a, s * (1.5 * r - 0.5 * r**3), s),
        "exp": s * (1 - np.exp(-r)),
        "gau": s * (1 - np.exp(-(r**2))),
    }
    for kind, g in expected.items():
        m = errfield.VariogramModel(f"{kind}(sill={s},range={a})")
        np.testing.assert_allclose(m.gamma(h), g, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(m(h.reshape(7, 1)), g.reshape(7, 1), rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(m.covariance(h), s - g, rtol=1e-12, atol=1e-14)
    nu = 1.5
    mat = errfield.VariogramModel(f"mat(sill={s},range={a},nu={nu})")
    hp = h[1:]
    closed = s * (1 - 2 ** (1 - nu) / gamma_fn(nu) * (hp / a) ** nu * kv(nu, hp / a))
    # At h/a = 1e-5 both sides compute 1 - (a number within 1e-10 of 1): absolute rounding of a few
    # eps x sill, so the comparison is absolute there (atol = 4 eps x sill) and relative elsewhere.
    np.testing.assert_allclose(mat.gamma(hp), closed, rtol=1e-10, atol=4 * np.finfo(float).eps * s)
    nug = errfield.VariogramModel("nug(0.5)")
    assert nug.gamma(0.0) == 0.0 and nug.gamma(1e-9) == 0.5
    assert isinstance(nug.gamma(3), float)


def test_model_errors():
    with pytest.raises(errfield.ArgumentError, match="sill"):
        errfield.VariogramModel("sph(sill=-1,range=3)")
    with pytest.raises(errfield.ArgumentError, match="h: lag"):
        errfield.VariogramModel("exp(1,2)").gamma(np.array([1.0, -2.0]))
    with pytest.raises(errfield.ArgumentError, match="unbounded"):
        errfield.VariogramModel("lin(slope=2)").covariance(1.0)


def sample_field(n=60, seed=11):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1000, size=(n, 2))
    # a smooth field plus noise: a realistic variogram with a range of a few hundred
    z = np.sin(x[:, 0] / 250.0) * np.cos(x[:, 1] / 300.0) + 0.05 * rng.standard_normal(n)
    return x, z


@pytest.mark.parametrize("kind,weights,nugget,cli_nugget", [("sph", "nj_h2", "free", "free"),
                                                            ("exp", "nj", None, "none"),
                                                            ("gau", "cressie", 0.001, "fixed=0.001")])
def test_wls_fit_matches_cli(tmp_path, kind, weights, nugget, cli_nugget):
    x, z = sample_field()
    samples = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "v": z})
    edges = np.linspace(0, 600, 13)
    run_cli("variogram", "--input", samples, "--coords", "x,y", "--value", "v",
            "--bins", ",".join(repr(float(e)) for e in edges), "--out", tmp_path / "v.csv")
    out = run_cli("fit-variogram", "--input", tmp_path / "v.csv", "--model", kind, "--weights", weights,
                  "--nugget", cli_nugget)
    v = errfield.variogram(x, z, edges)
    fit = errfield.fit_variogram(v, kind, weights=weights, nugget=nugget)
    assert str(fit["model"]) == out.splitlines()[0]
    assert fit["status"] in ("converged", "max_evaluations")
    assert fit["bins_used"] == int((v.pairs > 0).sum())
    # The reported SSE is the weighted SSE of the reported model, recomputed here.
    used = v.pairs > 0
    h, g, n = v.lag_mean[used], v.gamma[used], v.pairs[used].astype(float)
    model_g = fit["model"].gamma(h)
    w = {"nj": n, "nj_h2": n / h**2, "cressie": n / model_g**2}[weights]
    np.testing.assert_allclose(fit["weighted_sse"], np.sum(w * (g - model_g) ** 2), rtol=1e-9)


def numpy_nll(x, z, model, restricted):
    """The formula of include/errfield/kriging_likelihood.hpp for ordinary kriging, written again."""
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
    k = model.covariance(d)
    n = len(z)
    f = np.ones((n, 1))
    kinv_z = np.linalg.solve(k, z)
    kinv_f = np.linalg.solve(k, f)
    ftkf = f.T @ kinv_f
    beta = np.linalg.solve(ftkf, f.T @ kinv_z)
    r = z - (f @ beta)
    quad = r @ np.linalg.solve(k, r)
    logdet = np.linalg.slogdet(k)[1]
    if restricted:
        return 0.5 * (logdet + np.linalg.slogdet(ftkf)[1] + quad + (n - 1) * math.log(2 * math.pi))
    return 0.5 * (logdet + quad + n * math.log(2 * math.pi))


@pytest.mark.parametrize("method", ["reml", "ml"])
def test_likelihood_matches_numpy_and_fit_matches_cli(tmp_path, method):
    x, z = sample_field(n=40)
    model = errfield.VariogramModel("exp(sill=0.4,range=220)+nug(0.003)")
    nll = errfield.negative_log_likelihood(x, z, model, method=method)
    np.testing.assert_allclose(nll, numpy_nll(x, z, model, method == "reml"), rtol=1e-10)
    samples = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "v": z})
    out = run_cli("fit-variogram", "--input", samples, "--method", method, "--coords", "x,y", "--value", "v",
                  "--model", "exp")
    fit = errfield.fit_likelihood(x, z, "exp", method=method)
    assert str(fit["model"]) == out.splitlines()[0]
    # The optimum is at least as likely as the model we started from.
    assert fit["negative_log_likelihood"] <= nll + 1e-9
    np.testing.assert_allclose(errfield.negative_log_likelihood(x, z, fit["model"], method=method),
                               fit["negative_log_likelihood"], rtol=1e-12)


def test_fit_errors():
    x, z = sample_field(n=20)
    v = errfield.variogram(x, z, np.linspace(0, 600, 7))
    with pytest.raises(errfield.ArgumentError, match="nu: model 'mat' needs nu"):
        errfield.fit_variogram(v, "mat")
    with pytest.raises(errfield.ArgumentError, match="nugget"):
        errfield.fit_variogram(v, "sph", nugget="sometimes")
    with pytest.raises(TypeError, match="lag_mean"):
        errfield.fit_variogram({"gamma": 1}, "sph")
    with pytest.raises(errfield.ArgumentError, match="values"):
        errfield.fit_likelihood(x, np.c_[z, z], "exp")


def test_fit_from_a_model_text_improves_on_its_start():
    x, z = sample_field()
    v = errfield.variogram(x, z, np.linspace(0, 600, 13))
    start = errfield.VariogramModel("sph(sill=0.2,range=300)+nug(0.01)")
    fit = errfield.fit_variogram(v, str(start), weights="nj")
    assert [c["kind"] for c in fit["model"].components] == ["sph", "nug"]
    used = v.pairs > 0
    h, g, n = v.lag_mean[used], v.gamma[used], v.pairs[used].astype(float)
    start_sse = np.sum(n * (g - start.gamma(h)) ** 2)
    # the given parameters are one of the starting points, so the fit is at least as good
    assert fit["weighted_sse"] <= start_sse
    np.testing.assert_allclose(fit["weighted_sse"], np.sum(n * (g - fit["model"].gamma(h)) ** 2), rtol=1e-9)


def test_likelihood_sample_minimum_and_constant_values_are_the_clis(tmp_path):
    """Issue 20: Python said "need at least 3" samples where the CLI says 4; and values that are all
    equal "converged" to a sill of 8e-34. Both are refused, with one shared minimum."""
    from conftest import run_cli_status
    x, z = sample_field(n=20)
    samples = write_csv(tmp_path / "s.csv", {"x": x[:3, 0], "y": x[:3, 1], "v": z[:3]})
    status, _, stderr = run_cli_status("fit-variogram", "--input", samples, "--method", "reml", "--coords", "x,y",
                                       "--value", "v", "--model", "exp")
    assert status == 2 and "at least 4 samples" in stderr
    with pytest.raises(errfield.InputError, match="need at least 4"):
        errfield.fit_likelihood(x[:3], z[:3], "exp")
    with pytest.raises(errfield.InputError, match="values are equal"):
        errfield.fit_likelihood(x, np.full(len(z), 2.5), "exp")


def test_likelihood_sample_budget_is_the_clis():
    """The CLI refused more than 3,000 samples for the exact ML/REML (O(N^3) per evaluation, exit 3);
    Python went ahead (N = 10^5 would allocate 80 GB per matrix). One limit, a ResourceError before any
    work; beyond it the default (likelihood='auto') takes the Vecchia approximation."""
    rng = np.random.default_rng(3)
    x = rng.uniform(0, 100, size=(3001, 2))
    with pytest.raises(errfield.ResourceError, match="limited to 3000 samples"):
        errfield.fit_likelihood(x, rng.standard_normal(3001), "exp", likelihood="exact")
    with pytest.raises(errfield.ArgumentError, match="vecchia_neighbours"):
        errfield.fit_likelihood(x[:50], rng.standard_normal(50), "exp", vecchia_neighbours=0)


def test_vecchia_likelihood_with_every_predecessor_is_the_exact_one():
    """With as many neighbours as samples - 1 the Vecchia likelihood is exact (an identity)."""
    rng = np.random.default_rng(4)
    x = rng.uniform(0, 100, size=(40, 2))
    z = np.sin(x[:, 0] / 20.0) + 0.1 * rng.standard_normal(40)
    exact = errfield.fit_likelihood(x, z, "exp", likelihood="exact")
    vecchia = errfield.fit_likelihood(x, z, "exp", likelihood="vecchia", vecchia_neighbours=39)
    assert vecchia["negative_log_likelihood"] == pytest.approx(exact["negative_log_likelihood"], rel=1e-8)
    assert "Vecchia" in vecchia["message"]
