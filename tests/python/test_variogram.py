"""errfield.variogram against the CLI's `errfield variogram` CSV and a brute-force estimator."""
import numpy as np
import pytest

import errfield
from conftest import numbers, read_csv, run_cli, same, write_csv


def field(n=150, dims=3, k=1, seed=7):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 500.0, size=(n, dims))
    z = np.sin(x[:, :1] / 120.0) + 0.1 * rng.standard_normal((n, k))
    return x, z


@pytest.mark.parametrize(
    "estimator,convention,dims,k",
    [("matheron", "paper", 3, 1), ("cressie", "gstat", 2, 1), ("dowd", "paper", 6, 3), ("matheron", "gstat", 3, 3)],
)
def test_matches_cli_csv(tmp_path, estimator, convention, dims, k):
    x, z = field(dims=dims, k=k)
    coords = [f"c{i}" for i in range(dims)]
    values = [f"v{i}" for i in range(k)]
    cols = {c: x[:, i] for i, c in enumerate(coords)}
    cols.update({v: z[:, i] for i, v in enumerate(values)})
    samples = write_csv(tmp_path / "s.csv", cols)
    # 5000 is beyond every lag: its bin is empty (pairs 0, NaN gamma) on both sides.
    edges = [0.0, 25.0, 60.0, 100.0, 175.5, 250.0, 400.0, 5000.0, 6000.0]
    out = tmp_path / "v.csv"
    run_cli("variogram", "--input", samples, "--coords", ",".join(coords), "--value", ",".join(values),
            "--bins", ",".join(repr(e) for e in edges), "--estimator", estimator, "--convention", convention,
            "--out", out)
    csv = read_csv(out)
    v = errfield.variogram(x, z if k > 1 else z[:, 0], np.array(edges), estimator=estimator, convention=convention)
    for name in ("lag_lo", "lag_hi", "lag_mean", "gamma"):
        assert same(getattr(v, name), numbers(csv[name])), name
    assert v.pairs.dtype == np.uint64
    assert v.pairs.tolist() == [int(c) for c in csv["pairs"]]
    assert v.pairs[-1] == 0 and np.isnan(v.gamma[-1])
    assert v.component_gamma.shape == (len(edges) - 1, k)


def test_matheron_equals_brute_force():
    x, z = field(n=80, dims=2, k=2, seed=3)
    edges = np.array([0.0, 50.0, 120.0, 300.0, 800.0])
    v = errfield.variogram(x, z, edges)
    i, j = np.triu_indices(len(x), 1)
    h = np.linalg.norm(x[i] - x[j], axis=1)
    d2 = np.sum((z[i] - z[j]) ** 2, axis=1)
    for b in range(len(edges) - 1):
        inside = (h >= edges[b]) & (h < edges[b + 1])
        assert v.pairs[b] == inside.sum()
        np.testing.assert_allclose(v.gamma[b], 0.5 * d2[inside].mean(), rtol=1e-12)
        np.testing.assert_allclose(v.lag_mean[b], h[inside].mean(), rtol=1e-12)
        np.testing.assert_allclose(v.component_gamma[b].sum(), v.gamma[b], rtol=1e-12)


def test_one_dimensional_coords_and_integer_input():
    v = errfield.variogram(np.array([0, 1, 3]), np.array([0, 1, 3]), [0, 1.5, 2.5, 3.5])
    assert v.pairs.tolist() == [1, 1, 1]
    assert v.gamma.tolist() == [0.5, 2.0, 4.5]


def test_bad_arguments_name_the_argument():
    x, z = field(n=10)
    edges = [0.0, 100.0, 200.0]
    bad = x.copy()
    bad[4, 1] = np.nan
    with pytest.raises(errfield.ArgumentError, match=r"coords\[4, 1\] is nan"):
        errfield.variogram(bad, z, edges)
    with pytest.raises(errfield.ArgumentError, match=r"values: 9 rows but coords has 10"):
        errfield.variogram(x, z[:9], edges)
    with pytest.raises(errfield.ArgumentError, match=r"coords: array of shape \(2, 5, 2\) is 3-D"):
        errfield.variogram(np.zeros((2, 5, 2)), z, edges)
    with pytest.raises(TypeError, match=r"coords: dtype complex128"):
        errfield.variogram(x.astype(complex), z, edges)
    with pytest.raises(TypeError, match=r"values: dtype <U"):
        errfield.variogram(x, np.array(["a"] * 10), edges)
    with pytest.raises(errfield.ArgumentError, match=r"bins: array of shape \(1,\) has 1 rows; expected at least 2"):
        errfield.variogram(x, z, [1.0])
    with pytest.raises(errfield.ArgumentError, match="edge"):
        errfield.variogram(x, z, [0.0, 5.0, 5.0])  # the library names the offending edge
    with pytest.raises(errfield.ArgumentError, match="cressie"):
        errfield.variogram(x, z, edges, estimator="median")
    assert issubclass(errfield.ArgumentError, ValueError) and issubclass(errfield.ArgumentError, errfield.Error)
    assert issubclass(errfield.InputError, ValueError) and issubclass(errfield.Error, RuntimeError)


def test_library_messages_are_the_clis(tmp_path):
    from conftest import run_cli_status
    x, z = field(n=10, dims=1)
    samples = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "v": z[:, 0]})
    status, _, stderr = run_cli_status("variogram", "--input", samples, "--coords", "x", "--value", "v",
                                       "--bins", "0,5,5")
    assert status == 2
    prefix = "errfield: invalid argument: "
    assert stderr.startswith(prefix)
    with pytest.raises(errfield.ArgumentError) as e:
        errfield.variogram(x, z, [0.0, 5.0, 5.0])
    assert str(e.value) == stderr[len(prefix):].strip()


def test_thread_limit_is_the_clis(tmp_path):
    """Issue 20: threads=10**9 killed the interpreter (libgomp: Out of memory allocating 224 GB). The
    library's options refuse what the CLI's --threads refuses, with the same limit (ResourceError)."""
    from conftest import run_cli_status
    x, z = field(n=10, dims=1)
    samples = write_csv(tmp_path / "s.csv", {"x": x[:, 0], "v": z[:, 0]})
    status, _, stderr = run_cli_status("variogram", "--input", samples, "--coords", "x", "--value", "v",
                                       "--bins", "0,100,200", "--threads", str(10**9))
    assert status == 3
    limit = "at most 1024 threads per job"
    assert limit in stderr
    with pytest.raises(errfield.ResourceError, match=limit):
        errfield.variogram(x, z, [0.0, 100.0, 200.0], threads=10**9)
    with pytest.raises(errfield.ArgumentError, match="threads is -1"):
        errfield.variogram(x, z, [0.0, 100.0, 200.0], threads=-1)
    assert errfield.variogram(x, z, [0.0, 100.0, 200.0], threads=1024).pairs.sum() > 0


def test_cloud_and_map_match_a_brute_force():
    rng = np.random.default_rng(36)
    x = rng.uniform(0.0, 100.0, size=(50, 2))
    z = rng.standard_normal(50)
    c = errfield.variogram_cloud(x, z, cutoff=30.0)
    pairs = [(i, j) for i in range(50) for j in range(i) if np.linalg.norm(x[i] - x[j]) <= 30.0]
    assert list(zip(c["left"].tolist(), c["right"].tolist())) == pairs
    np.testing.assert_allclose(c["gamma"], [0.5 * (z[i] - z[j]) ** 2 for i, j in pairs], rtol=1e-14)
    with pytest.raises(errfield.ResourceError):
        errfield.variogram_cloud(x, z, cutoff=30.0, max_pairs=len(pairs) - 1)
    m = errfield.variogram_map(x, z, cutoff=40.0, width=(10.0, 20.0))
    assert m["gamma"].shape == (len(m["dy"]), len(m["dx"])) == (5, 9)
    n = np.zeros_like(m["pairs"])
    for i in range(50):
        for j in range(50):
            if i != j:
                s = x[i] - x[j]
                col = np.nonzero(np.abs(s[0] - m["dx"]) < 5.0)[0]
                row = np.nonzero(np.abs(s[1] - m["dy"]) < 10.0)[0]
                if len(col) and len(row):
                    n[row[0], col[0]] += 1
    np.testing.assert_array_equal(m["pairs"], n)
