"""Kriging, ScatteredIdw and GridIdw against `errfield interpolate` / `errfield cv` on the same data,
and against second implementations written here with NumPy (GP posterior, IDW by brute force)."""
import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, run_cli_status, same, write_csv

MODEL = "exp(sill=0.5,range=300)+nug(0.01)"


def data(n=50, m=30, k=1, seed=5):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1000, size=(n, 2))
    z = np.sin(x[:, :1] / 200.0) + np.cos(x[:, 1:] / 300.0) * np.arange(1, k + 1) + 0.05 * rng.standard_normal((n, k))
    t = rng.uniform(-50, 1050, size=(m, 2))
    return x, (z[:, 0] if k == 1 else z), t


def write_samples(tmp_path, x, z, t):
    cols = {"x": x[:, 0], "y": x[:, 1]}
    names = ["v"] if z.ndim == 1 else [f"v{c}" for c in range(z.shape[1])]
    if z.ndim == 1:
        cols["v"] = z
    else:
        cols.update({n: z[:, c] for c, n in enumerate(names)})
    s = write_csv(tmp_path / "s.csv", cols)
    tt = write_csv(tmp_path / "t.csv", {"x": t[:, 0], "y": t[:, 1]})
    return s, tt, names


@pytest.mark.parametrize("kind,extra,cli_extra", [
    ("ordinary", {}, []),
    ("simple", {"mean": 0.7}, ["--mean", "0.7"]),
    ("universal1", {}, []),
    ("ordinary", {"backend": "local", "neighbors": 12}, ["--backend", "local", "--neighbors", "12"]),
    # No backend but a neighbourhood: the local back end, for both (one shared option mapping).
    ("ordinary", {"neighbors": 9, "radius": 400.0}, ["--neighbors", "9", "--radius", "400"]),
    # gstat's nmin and omax: the same words on both sides (targets with too few neighbours: NaN / empty).
    ("ordinary", {"radius": 250.0, "min_neighbours": 4, "octant_max": 2},
     ["--radius", "250", "--min-neighbours", "4", "--octant-max", "2"]),
])
def test_kriging_matches_cli(tmp_path, kind, extra, cli_extra):
    x, z, t = data()
    s, tt, _ = write_samples(tmp_path, x, z, t)
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "v",
            "--model", MODEL, "--kind", kind, *cli_extra, "--out", tmp_path / "o.csv")
    csv = read_csv(tmp_path / "o.csv")
    mean, var = errfield.Kriging(x, z, MODEL, kind=kind, **extra).predict(t)
    assert mean.shape == (len(t),) and var.shape == (len(t),)
    assert same(mean, numbers(csv["pred"]))
    assert same(var, numbers(csv["var"]))


def test_local_radius_includes_samples_at_exactly_the_radius():
    # An integer grid without the target points: each has 4 samples at exactly 2 (gstat's maxdist
    # keeps them). Local kriging within radius 2 = dense kriging of the samples at distance <= 2.
    g = np.array([(i, j) for i in range(9) for j in range(9) if (i, j) not in ((4, 4), (1, 6))], dtype=float)
    z = np.sin(0.6 * g[:, 0]) + 0.2 * g[:, 1]
    for target in ([4.0, 4.0], [1.0, 6.0]):
        inside = ((g - target) ** 2).sum(axis=1) <= 4.0
        local = errfield.Kriging(g, z, MODEL, radius=2.0).predict(np.array([target]))
        dense = errfield.Kriging(g[inside], z[inside], MODEL).predict(np.array([target]))
        assert np.allclose(local[0], dense[0], rtol=0, atol=1e-10)
        assert np.allclose(local[1], dense[1], rtol=0, atol=1e-10)


def test_vector_values_match_cli_and_componentwise_kriging(tmp_path):
    x, z, t = data(k=3)
    s, tt, names = write_samples(tmp_path, x, z, t)
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y",
            "--value", ",".join(names), "--model", MODEL, "--out", tmp_path / "o.csv")
    csv = read_csv(tmp_path / "o.csv")
    mean, var = errfield.Kriging(x, z, errfield.VariogramModel(MODEL)).predict(t)
    assert mean.shape == (len(t), 3)
    for c, name in enumerate(names):
        assert same(mean[:, c], numbers(csv[f"pred_{name}"]))
        one, one_var = errfield.Kriging(x, z[:, c], MODEL).predict(t)
        np.testing.assert_allclose(mean[:, c], one, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(var, one_var, rtol=1e-10, atol=1e-12)


def test_simple_kriging_is_the_gp_posterior():
    x, z, t = data(n=40, m=25)
    model = errfield.VariogramModel(MODEL)
    mu = 0.3
    mean, var = errfield.Kriging(x, z, model, kind="simple", mean=mu).predict(t)
    # Gaussian-process posterior with covariance C(h) = sill - gamma(h), nugget at zero lag only.
    k = model.covariance(np.linalg.norm(x[:, None] - x[None], axis=2))
    ks = model.covariance(np.linalg.norm(t[:, None] - x[None], axis=2))
    gp_mean = mu + ks @ np.linalg.solve(k, z - mu)
    gp_var = model.sill - np.einsum("ij,ji->i", ks, np.linalg.solve(k, ks.T))
    np.testing.assert_allclose(mean, gp_mean, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(var, gp_var, rtol=1e-9, atol=1e-11)


def test_ordinary_kriging_equals_the_bordered_system():
    x, z, t = data(n=35, m=20, seed=9)
    model = errfield.VariogramModel("sph(sill=0.4,range=500)+nug(0.02)")
    mean, var = errfield.Kriging(x, z, model).predict(t)
    n = len(x)
    a = np.zeros((n + 1, n + 1))
    a[:n, :n] = model.covariance(np.linalg.norm(x[:, None] - x[None], axis=2))
    a[:n, n] = a[n, :n] = 1.0
    b = np.ones((n + 1, len(t)))
    b[:n] = model.covariance(np.linalg.norm(x[:, None] - t[None], axis=2))
    sol = np.linalg.solve(a, b)
    np.testing.assert_allclose(mean, sol[:n].T @ z, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(var, model.sill - np.sum(sol * b, axis=0), rtol=1e-8, atol=1e-11)


@pytest.mark.parametrize("folds,cli_folds", [("loo", "loo"), (5, "5")])
def test_kriging_cross_validation_matches_cli(tmp_path, folds, cli_folds):
    x, z, t = data()
    s, _, _ = write_samples(tmp_path, x, z, t)
    run_cli("cv", "--method", "kriging", "--samples", s, "--coords", "x,y", "--value", "v", "--model", MODEL,
            "--folds", cli_folds, *([] if folds == "loo" else ["--seed", "3"]), "--out", tmp_path / "cv.csv")
    csv = read_csv(tmp_path / "cv.csv")
    cv = errfield.Kriging(x, z, MODEL).cross_validate(folds, seed=3)
    assert same(cv.prediction, numbers(csv["pred"]))
    assert same(cv.residual, numbers(csv["residual"]))
    assert same(cv.variance, numbers(csv["var"]))
    assert cv.fold.tolist() == [int(f) for f in csv["fold"]]
    np.testing.assert_allclose(cv.rms_error, np.sqrt(np.mean(cv.residual**2)), rtol=1e-12)
    assert cv.mean_squared_z is not None


def test_scattered_idw_matches_cli_and_brute_force(tmp_path):
    x, z, t = data()
    s, tt, _ = write_samples(tmp_path, x, z, t)
    run_cli("interpolate", "--method", "idw", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "v",
            "--power", "2", "--neighbors", "8", "--out", tmp_path / "o.csv")
    pred = errfield.ScatteredIdw(x, z, power=2, neighbors=8).predict(t)
    assert same(pred, numbers(read_csv(tmp_path / "o.csv")["pred"]))
    d = np.linalg.norm(t[:, None] - x[None], axis=2)
    near = np.argsort(d, axis=1)[:, :8]
    w = 1.0 / np.take_along_axis(d, near, axis=1) ** 2
    np.testing.assert_allclose(pred, np.sum(w * z[near], axis=1) / w.sum(axis=1), rtol=1e-12)
    run_cli("cv", "--method", "idw", "--samples", s, "--coords", "x,y", "--value", "v", "--neighbors", "8",
            "--folds", "4", "--out", tmp_path / "cv.csv")
    cv = errfield.ScatteredIdw(x, z, neighbors=8).cross_validate(4)
    assert same(cv.prediction, numbers(read_csv(tmp_path / "cv.csv")["pred"]))
    assert cv.variance is None


def grid_data():
    g = np.arange(0.0, 500.1, 125.0)
    xx, yy, zz = np.meshgrid(g, g, g, indexing="ij")
    nodes = np.c_[xx.ravel(), yy.ravel(), zz.ravel()]
    rng = np.random.default_rng(2)
    nodes = nodes[rng.permutation(len(nodes))]  # any order
    values = 0.01 * nodes[:, 0] - 0.002 * nodes[:, 2] + 0.1 * rng.standard_normal(len(nodes))
    targets = rng.uniform(0, 500, size=(40, 3))
    return nodes, values, targets


def test_grid_idw_matches_cli(tmp_path):
    nodes, values, targets = grid_data()
    s = write_csv(tmp_path / "s.csv", {"x": nodes[:, 0], "y": nodes[:, 1], "z": nodes[:, 2], "d": values})
    tt = write_csv(tmp_path / "t.csv", {"x": targets[:, 0], "y": targets[:, 1], "z": targets[:, 2]})
    run_cli("interpolate", "--method", "idw-grid", "--samples", s, "--targets", tt, "--coords", "x,y,z",
            "--value", "d", "--out", tmp_path / "o.csv")
    idw = errfield.GridIdw(nodes, values)
    assert same(idw.predict(targets), numbers(read_csv(tmp_path / "o.csv")["pred"]))
    assert idw.grid["counts"] == (5, 5, 5)
    # exact at a node
    assert idw.predict(nodes[:3]).tolist() == values[:3].tolist()
    with pytest.raises(errfield.OutsideGridError, match="outside") as e:
        idw.predict(np.array([[10.0, 10.0, 10.0], [600.0, 10.0, 10.0]]))
    assert isinstance(e.value, errfield.InputError) and e.value.row is None
    assert np.isfinite(errfield.GridIdw(nodes, values, clamp=True).predict([[600.0, 10.0, 10.0]])).all()


def test_interpolation_errors():
    x, z, t = data(n=10)
    with pytest.raises(errfield.ArgumentError, match=r"targets: array of shape \(4, 3\) has 3 columns; expected 2"):
        errfield.Kriging(x, z, MODEL).predict(np.zeros((4, 3)))
    with pytest.raises(errfield.ArgumentError, match=r"kind simple needs the known mean \(mean\)"):
        errfield.Kriging(x, z, MODEL, kind="simple")
    with pytest.raises(errfield.ArgumentError, match="dense"):
        errfield.Kriging(x, z, MODEL, backend="gpu")
    bad = z.copy()
    bad[3] = np.inf
    with pytest.raises(errfield.ArgumentError, match=r"values\[3\] is inf"):
        errfield.ScatteredIdw(x, bad)
    with pytest.raises(errfield.ArgumentError, match="values: 4 columns"):
        errfield.Kriging(x, np.zeros((10, 4)), MODEL)
    dup = np.r_[x, x[:1]]
    with pytest.raises(errfield.InputError):
        errfield.Kriging(dup, np.r_[z, z[:1]], MODEL)


@pytest.mark.parametrize("extra,cli_extra,message", [
    ({"backend": "dense", "neighbors": 5}, ["--backend", "dense", "--neighbors", "5"],
     "neighbors/{p}radius select the neighbourhood of {p}backend local, not {p}backend dense"),
    ({"kind": "kriged"}, ["--kind", "kriged"], "{p}kind is 'kriged'; expected simple, ordinary"),
    ({"nugget": "both"}, ["--nugget-as", "both"], "is 'both'; expected micro or error"),
    ({"kind": "ordinary", "mean": 1.0}, ["--mean", "1"], "mean applies to {p}kind simple only"),
])
def test_kriging_option_words_refused_alike_by_cli_and_python(tmp_path, extra, cli_extra, message):
    x, z, t = data(n=12)
    s, tt, _ = write_samples(tmp_path, x, z, t)
    status, _, err = run_cli_status("interpolate", "--method", "kriging", "--samples", s, "--targets", tt,
                                    "--coords", "x,y", "--value", "v", "--model", MODEL, *cli_extra,
                                    "--out", tmp_path / "o.csv")
    assert status == 2 and message.format(p="--") in err
    with pytest.raises(errfield.ArgumentError) as e:
        errfield.Kriging(x, z, MODEL, **extra)
    assert message.format(p="") in str(e.value)


def test_thread_limit_is_the_clis():
    """Issue 20: threads=10**9 reached OpenMP, which aborted the interpreter; the estimators refuse it
    as the CLI's --threads does (one shared check, errfield/thread_count.hpp)."""
    x, z, t = data(n=20, m=3)
    limit = "at most 1024 threads per job"
    with pytest.raises(errfield.ResourceError, match=limit):
        errfield.Kriging(x, z, MODEL, threads=10**9)
    with pytest.raises(errfield.ResourceError, match=limit):
        errfield.ScatteredIdw(x, z, threads=10**9)
    g = np.array([[i, j, k] for i in range(2) for j in range(2) for k in range(2)], dtype=float)
    with pytest.raises(errfield.ResourceError, match=limit):
        errfield.GridIdw(g, np.arange(8.0), threads=10**9).predict(g)


def test_simulate_matches_cli_and_the_kriging_moments(tmp_path):
    # The draws are the CLI's for the same seed (the CSV holds shortest round-trip numbers), and
    # over many draws their mean and variance are the kriging's (within 5 standard errors).
    x, z, t = data(n=40, m=12)
    s, tt, _ = write_samples(tmp_path, x, z, t)
    k = errfield.Kriging(x, z, MODEL)
    draws = k.simulate(t, 3, seed=4)
    assert draws.shape == (3, 12)
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "v",
            "--model", MODEL, "--simulations", "3", "--seed", "4", "--out", tmp_path / "p.csv")
    out = read_csv(tmp_path / "p.csv")
    for d in range(3):
        assert np.array_equal(numbers(out[f"sim{d + 1}"]), draws[d])
    many = k.simulate(t, 800, seed=9)
    mean, var = k.predict(t)
    assert np.all(np.abs(many.mean(axis=0) - mean) <= 5 * np.sqrt(var / 800))
    assert np.all(np.abs(many.var(axis=0, ddof=1) / var - 1) <= 5 * np.sqrt(2 / 799))
    vec = errfield.Kriging(x, np.column_stack([z, 2 * z]), MODEL).simulate(t, 2, method="sequential", neighbours=10)
    assert vec.shape == (2, 12, 2)
    with pytest.raises(errfield.ArgumentError):
        k.simulate(t, 2, method="turning-bands")


def test_block_prediction_matches_cli(tmp_path):
    # predict(block=...) is `interpolate --block`, and a block is known better than a point.
    x, z, t = data(n=40, m=12)
    s, tt, _ = write_samples(tmp_path, x, z, t)
    k = errfield.Kriging(x, z, MODEL)
    mean, var = k.predict(t, block=[40.0, 60.0], block_points=3, block_rule="regular")
    run_cli("interpolate", "--method", "kriging", "--samples", s, "--targets", tt, "--coords", "x,y", "--value", "v",
            "--model", MODEL, "--block", "40,60", "--block-points", "3", "--block-rule", "regular",
            "--out", tmp_path / "p.csv")
    out = read_csv(tmp_path / "p.csv")
    assert same(mean, numbers(out["pred"]))
    assert same(var, numbers(out["var"]))
    assert np.all(var < k.predict(t)[1])
    with pytest.raises(errfield.ArgumentError):
        k.predict(t, block=[40.0])


def test_indicator_kriging_is_kriging_of_the_strict_indicators_then_gslib_order_correction():
    rng = np.random.default_rng(3606)
    x = rng.uniform(0.0, 10.0, size=(40, 2))
    z = np.round(rng.uniform(0.0, 10.0, size=40))  # integers: some equal to a threshold
    t = rng.uniform(0.0, 10.0, size=(20, 2))
    models = ["sph(sill=0.15,range=4)+nug(0.05)", "exp(sill=0.2,range=1)+nug(0.02)", "sph(sill=0.1,range=3)+nug(0.08)"]
    r = errfield.indicator_kriging(x, z, t, [3.0, 5.0, 7.0], models)
    for k, (threshold, model) in enumerate(zip([3.0, 5.0, 7.0], models)):
        mean, var = errfield.Kriging(x, (z < threshold).astype(float), model).predict(t)
        np.testing.assert_array_equal(r["raw"][:, k], mean)
        np.testing.assert_array_equal(r["variance"][:, k], var)
    q = np.clip(r["raw"], 0.0, 1.0)
    up = np.maximum.accumulate(q, axis=1)
    down = np.minimum.accumulate(q[:, ::-1], axis=1)[:, ::-1]
    np.testing.assert_allclose(r["probability"], 0.5 * (up + down), atol=1e-15)
