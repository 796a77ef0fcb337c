"""Peer of errfield's likelihood fits: scikit-learn's GaussianProcessRegressor with an ARD Matern
kernel times a constant plus a WhiteKernel, zero mean (errfield: --kind simple0, --method ml).

Usage: sklearn_gp.py TRAIN.csv TEST.csv COORDS VALUES MODEL.json
Prints JSON: the negative log-likelihood sklearn computes at errfield's parameters, sklearn's own
optimum (from several starts) and the held-out RMS of its predictions on TEST.csv.

Parameter map: gstat's Matern range a multiplies the lag as h/a, sklearn's length scale l as
sqrt(2 nu) h/l, so l_k = sqrt(2 nu) a_k for each coordinate k; sill -> ConstantKernel, nugget ->
WhiteKernel. alpha=0 so that the covariance is exactly errfield's.
"""
import json
import sys

import numpy as np
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel


def read(path, coords, values):
    with open(path) as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    x = data[:, [header.index(c) for c in coords]]
    y = data[:, [header.index(v) for v in values]]
    return x, (y[:, 0] if y.shape[1] == 1 else y)


def main():
    train, test, coords, values, model_path = sys.argv[1:6]
    coords, values = coords.split(","), values.split(",")
    x, y = read(train, coords, values)
    xt, yt = read(test, coords, values)
    model = json.load(open(model_path))
    comps = model["components"]
    mat = next(c for c in comps if c["kind"] in ("mat", "exp"))
    nu = mat.get("nu", 0.5)
    nugget = sum(c["sill"] for c in comps if c["kind"] == "nug")
    ranges = np.array(model["fit"]["ranges"], dtype=float)
    if ranges.size == 1:
        ranges = np.full(x.shape[1], ranges[0])
    length = np.sqrt(2.0 * nu) * ranges
    kernel = ConstantKernel(mat["sill"], (1e-5, 1e5)) * Matern(length, (1e-5, 1e5), nu=nu) + \
        WhiteKernel(nugget, (1e-9, 1e5))
    at_ours = GaussianProcessRegressor(kernel=kernel, alpha=0.0, optimizer=None).fit(x, y)
    nll_at_errfield = -at_ours.log_marginal_likelihood(at_ours.kernel_.theta)

    # sklearn's own fit from a neutral start (unit sill, length scales = the extent, small noise).
    start = ConstantKernel(1.0, (1e-5, 1e5)) * Matern(np.ptp(x, axis=0), (1e-5, 1e5), nu=nu) + \
        WhiteKernel(0.01, (1e-9, 1e5))
    gp = GaussianProcessRegressor(kernel=start, alpha=0.0, n_restarts_optimizer=3, random_state=0).fit(x, y)
    nll_sklearn = -gp.log_marginal_likelihood_value_
    pred = gp.predict(xt)
    err = (pred - yt).reshape(len(xt), -1)
    print(json.dumps({
        "nll_at_errfield": float(nll_at_errfield),
        "nll_sklearn": float(nll_sklearn),
        "heldout_rms_sklearn": float(np.sqrt((err ** 2).sum(axis=1).mean())),
        "kernel_sklearn": str(gp.kernel_),
    }))


if __name__ == "__main__":
    main()
