"""errfield.cross_variogram and errfield.fit_lmc against a brute-force loop and the CLI
(`variogram --cross`, `fit-variogram --lmc`) on the same simulated data."""
import json

import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, write_csv


def field(n=120, seed=3):
    # Simulated: 2-D points, three correlated components.
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 600.0, size=(n, 2))
    s = np.sin(x[:, 0] / 90.0) * np.cos(x[:, 1] / 140.0)
    z = np.column_stack([s, -0.6 * s, 0.9 * s]) + 0.2 * rng.standard_normal((n, 3))
    return x, z


def test_cross_variogram_matches_a_double_loop():
    x, z = field()
    edges = np.arange(0.0, 450.0, 50.0)
    v = errfield.cross_variogram(x, z, edges)
    assert v["gamma"].shape == (len(edges) - 1, 3, 3)
    assert v["pairs"].dtype == np.uint64
    total = np.zeros((len(edges) - 1, 3, 3))
    scale = np.zeros_like(total)
    count = np.zeros(len(edges) - 1)
    for i in range(len(x)):
        for j in range(i):
            h = np.linalg.norm(x[i] - x[j])
            k = np.searchsorted(edges, h, side="right") - 1
            if 0 <= k < len(edges) - 1:
                d = z[i] - z[j]
                total[k] += np.outer(d, d)
                scale[k] += np.abs(np.outer(d, d))
                count[k] += 1
    assert v["pairs"].tolist() == count.astype(int).tolist()
    expected = total / (2.0 * count[:, None, None])
    assert np.all(np.abs(v["gamma"] - expected) <= 1e-13 * scale / (2.0 * count[:, None, None]))


def test_cross_variogram_and_fit_lmc_agree_with_the_cli(tmp_path):
    x, z = field()
    samples = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "y": x[:, 1], "ex": z[:, 0], "ey": z[:, 1], "ez": z[:, 2]})
    out = tmp_path / "v.csv"
    run_cli("variogram", "--input", samples, "--coords", "x,y", "--value", "ex,ey,ez", "--bins", "0:450:50",
            "--cross", "--out", out)
    csv = read_csv(out)
    v = errfield.cross_variogram(x, z, np.arange(0.0, 451.0, 50.0))
    names = ["ex", "ey", "ez"]
    for a in range(3):
        for b in range(a, 3):
            column = f"gamma_{names[a]}" if a == b else f"gamma_{names[a]}_{names[b]}"
            assert np.array_equal(v["gamma"][:, a, b], numbers(csv[column])), column
            assert np.array_equal(v["gamma"][:, b, a], v["gamma"][:, a, b])
    for method in ("goulard-voltz", "gstat"):
        lmc_json = tmp_path / f"{method}.json"
        run_cli("fit-variogram", "--lmc", "--input", out, "--value", "ex,ey,ez", "--model", "nug(0)+sph(1,300)",
                "--lmc-method", method, "--out", lmc_json)
        fit = errfield.fit_lmc(v, "nug(0)+sph(1,300)", method=method, names=names)
        written = json.loads(lmc_json.read_text())
        assert written["components"] == names
        assert json.loads(fit["json"])["components"] == names
        for k, s in enumerate(fit["structures"]):
            assert s["kind"] == written["structures"][k]["kind"]
            assert np.allclose(s["sills"], np.array(written["structures"][k]["sills"]), rtol=0, atol=1e-12)
            assert np.all(np.linalg.eigvalsh(s["sills"]) >= -1e-12)
        assert fit["weighted_residual"] == pytest.approx(written["fit"]["weighted_residual"], rel=1e-12)
        assert len(fit["smallest_eigenvalue_before_projection"]) == 2


def test_fit_lmc_fits_ranges_and_rejects_misuse():
    x, z = field()
    v = errfield.cross_variogram(x, z, np.arange(0.0, 451.0, 50.0))
    fit = errfield.fit_lmc(v, "nug+sph", weights="nj")
    assert fit["structures"][1]["range"] > 0.0
    with pytest.raises(errfield.ArgumentError, match="pow has no sill"):
        errfield.fit_lmc(v, "nug+pow")
    with pytest.raises(errfield.ArgumentError, match="goulard-voltz or gstat"):
        errfield.fit_lmc(v, "nug(0)+sph(1,300)", method="fast")
    # Issue 35: a Matern nu of 1e8 hung the fit and 1e10 threw from the Bessel function.
    for nu in (1e10, 1e8, 101.0):
        with pytest.raises(errfield.ArgumentError, match="0 < nu <= 100"):
            errfield.fit_lmc(v, "nug+mat", nu=nu)
    with pytest.raises(errfield.ArgumentError, match="at least 2 components"):
        errfield.cross_variogram(x, z[:, :1], np.arange(0.0, 451.0, 50.0))
