"""Anisotropic (ARD) models through the binding: the '@ard(...)' model text in Kriging, checked against
isotropic kriging on rescaled coordinates (the definition of ARD, docs/geostatistics.md) and against
`errfield interpolate`; the REML fit with anisotropy='ard' against `errfield fit-variogram
--method reml --anisotropy ard`."""
import json

import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, same, write_csv


def field(n=60, m=25, seed=3):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1000, size=(n, 2))
    # short correlation along x, long along y
    z = np.sin(x[:, 0] / 90.0) + np.cos(x[:, 1] / 700.0) + 0.02 * rng.standard_normal(n)
    t = rng.uniform(0, 1000, size=(m, 2))
    return x, z, t


def test_ard_model_is_isotropic_kriging_on_rescaled_coordinates():
    x, z, t = field()
    scales = np.array([0.2, 1.5])
    ard = errfield.Kriging(x, z, "exp(sill=0.8,range=300)+nug(0.001)@ard(0.2,1.5)")
    iso = errfield.Kriging(x / scales, z, "exp(sill=0.8,range=300)+nug(0.001)")
    mean, var = ard.predict(t)
    mean_iso, var_iso = iso.predict(t / scales)
    # Same system up to the rounding of the scaled distances (a few ulps, amplified by the
    # condition number reported by the factorization).
    tol = 1e-13 * max(1.0, ard.report["condition_number"])
    np.testing.assert_allclose(mean, mean_iso, rtol=0, atol=tol * np.abs(z).max())
    np.testing.assert_allclose(var, var_iso, rtol=0, atol=tol)
    # and not the isotropic model: the anisotropy matters here
    assert np.abs(mean - errfield.Kriging(x, z, "exp(sill=0.8,range=300)+nug(0.001)").predict(t)[0]).max() > 1e-3


def test_reml_ard_fit_matches_cli_and_kriges_alike(tmp_path):
    x, z, t = field()
    s = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "v": z})
    tt = write_csv(tmp_path / "t.csv", {"x": t[:, 0], "y": t[:, 1]})
    run_cli("fit-variogram", "--method", "reml", "--anisotropy", "ard", "--input", s, "--coords", "x,y",
            "--value", "v", "--model", "exp", "--out", tmp_path / "m.json")
    cli = json.loads((tmp_path / "m.json").read_text())["fit"]
    r = errfield.fit_likelihood(x, z, "exp", method="reml", anisotropy="ard")
    assert "@ard(" in str(r["model"])
    assert same(r["ranges"], np.array(cli["ranges"]))
    assert r["negative_log_likelihood"] == cli["negative_log_likelihood"]
    assert r["aic"] == cli["aic"] and r["parameters"] == cli["parameters"]
    # the field is shorter-ranged along x than along y
    assert r["ranges"][0] < r["ranges"][1]
    # The fitted model kriges as the CLI kriges with the model file.
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y",
            "--value", "v", "--model", tmp_path / "m.json", "--out", tmp_path / "o.csv")
    out = read_csv(tmp_path / "o.csv")
    mean, var = errfield.Kriging(x, z, r["model"]).predict(t)
    assert same(mean, numbers(out["pred"])) and same(var, numbers(out["var"]))
    # The model text round-trips through the parser.
    assert str(errfield.VariogramModel(str(r["model"]))) == str(r["model"])


def test_reml_rotated_fit_matches_cli(tmp_path):
    rng = np.random.default_rng(5)
    x = rng.uniform(0, 1000, size=(50, 2))
    # decorrelates fastest across the direction 30 deg clockwise from +y
    u = x[:, 0] * np.cos(np.radians(30)) - x[:, 1] * np.sin(np.radians(30))
    z = np.sin(u / 120.0) + 0.02 * rng.standard_normal(50)
    s = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "v": z})
    run_cli("fit-variogram", "--method", "reml", "--anisotropy", "rotated", "--input", s, "--coords", "x,y",
            "--value", "v", "--model", "exp", "--out", tmp_path / "m.json")
    cli = json.loads((tmp_path / "m.json").read_text())["fit"]
    r = errfield.fit_likelihood(x, z, "exp", method="reml", anisotropy="rotated")
    assert "@anis(" in str(r["model"])
    assert r["negative_log_likelihood"] == cli["negative_log_likelihood"]
    assert same(r["angles_deg"], np.array(cli["angles_deg"]))
    assert same(r["ranges"], np.array(cli["ranges"]))
    assert r["angles_deg"].shape == (1,) and r["angle_standard_errors_deg"].shape == (1,)


def test_anisotropy_errors():
    x, z, _ = field(n=10)
    with pytest.raises(errfield.ArgumentError, match="anisotropy: 'geometric'; expected 'none', 'ard' or 'rotated'"):
        errfield.fit_likelihood(x, z, "exp", anisotropy="geometric")
    with pytest.raises(errfield.ArgumentError):
        errfield.Kriging(x, z, "exp(sill=1,range=100)@ard(1,2,3)")  # 3 scales for 2-D coordinates
