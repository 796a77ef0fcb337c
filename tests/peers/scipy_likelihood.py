#!/usr/bin/python3
"""Independent ML/REML of an exponential covariance + nugget with a constant mean (ordinary
kriging's likelihood), written from the textbook formulas with numpy and optimized by scipy's
Nelder-Mead from several starts. Peer of `errfield fit-variogram --method ml|reml`.

usage: scipy_likelihood.py data.csv errfield_model.json reml|ml
prints JSON: scipy's best parameters and objective, and the objective at errfield's parameters.
"""
import json
import sys

import numpy as np
from scipy.optimize import minimize


def main():
    data_csv, model_json, method = sys.argv[1], sys.argv[2], sys.argv[3]
    a = np.loadtxt(data_csv, delimiter=",", skiprows=1)
    x, z = a[:, :3], a[:, 3]
    n = len(z)
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
    f = np.ones((n, 1))
    reml = method == "reml"

    def nll(sill, rng, nugget):
        c = sill * np.exp(-d / rng) + nugget * np.eye(n)
        try:
            l = np.linalg.cholesky(c)
        except np.linalg.LinAlgError:
            return np.inf
        ci_f = np.linalg.solve(c, f)
        ci_z = np.linalg.solve(c, z)
        g = f.T @ ci_f
        beta = np.linalg.solve(g, f.T @ ci_z)
        r = z - f @ beta
        q = r @ np.linalg.solve(c, r)
        logdet = 2.0 * np.log(np.diag(l)).sum()
        if reml:
            return 0.5 * (logdet + np.log(np.linalg.det(g)) + q + (n - 1) * np.log(2 * np.pi))
        return 0.5 * (logdet + q + n * np.log(2 * np.pi))

    var = float(np.var(z))
    span = float(d.max())
    best = None
    for s0, r0, g0 in [(var, span / 4, var * 0.05), (var / 2, span / 10, var * 0.2), (var * 2, span, var * 0.01)]:
        res = minimize(lambda t: nll(*np.exp(t)), np.log([s0, r0, g0]), method="Nelder-Mead",
                       options=dict(xatol=1e-9, fatol=1e-11, maxiter=20000, maxfev=20000))
        if best is None or res.fun < best.fun:
            best = res

    model = json.load(open(model_json))
    comps = {c["kind"]: c for c in model["components"]}
    ours = nll(comps["exp"]["sill"], comps["exp"]["range"], comps["nug"]["sill"])
    sill, rng, nugget = np.exp(best.x)
    print(json.dumps({"scipy": {"sill": sill, "range": rng, "nugget": nugget, "objective": best.fun},
                      "objective_at_errfield": ours}))


if __name__ == "__main__":
    main()
