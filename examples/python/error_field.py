#!/usr/bin/env python3
"""errfield from Python, notebook style: joints -> FK -> an error field -> variogram -> model fit ->
kriging with cross-validation -> a map of the predicted error and its standard deviation; then the
robot pipeline on measured joints and positions as columns: fit a compensation model, validate it
on held-out points, and the joints to send (errfield.fit / validate / compensate, as the CLI).

The "measurements" are SIMULATED: the nominal ER20-C10 with a smooth position-dependent error
added here (no hardware is involved). Run from a build tree:

    PYTHONPATH=build/python /usr/bin/python3 examples/python/error_field.py --out error_field.png
"""
import argparse

import matplotlib

matplotlib.use("Agg")  # files only; no display needed
import matplotlib.pyplot as plt
import numpy as np

import errfield


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="error_field.png", help="PNG to write")
    parser.add_argument("--samples", type=int, default=200, help="simulated measurements")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)

    # 1. Joints (deg) within 60 % of the limits, tool positions (mm) by forward kinematics.
    robot = errfield.Robot.builtin("er20_c10")
    q = rng.uniform(0.6 * robot.q_min, 0.6 * robot.q_max, size=(args.samples, 6))
    nominal = robot.position(q)  # (N, 3) mm

    # 2. SIMULATED measured error: a smooth field over the workspace (mm) plus tracker noise.
    def true_error(p):
        return 0.3 * np.sin(p[:, 0] / 400.0) + 0.2 * np.cos(p[:, 1] / 300.0) + 1e-4 * p[:, 2]

    error = true_error(nominal) + 0.01 * rng.standard_normal(len(nominal))

    # 3. Empirical variogram in task space (lags mm, gamma mm^2) and a fitted model.
    span = np.linalg.norm(nominal.max(axis=0) - nominal.min(axis=0))
    edges = np.linspace(0.0, span / 2, 16)
    vario = errfield.variogram(nominal, error, edges)
    fit = errfield.fit_variogram(vario, "sph")
    model = fit["model"]
    print(f"fitted model: {model}  (weighted SSE {fit['weighted_sse']:.3g}, {fit['status']})")

    # 4. Ordinary kriging: leave-one-out cross-validation, then predictions on a horizontal slice.
    kriging = errfield.Kriging(nominal, error, model)
    cv = kriging.cross_validate("loo")
    print(f"leave-one-out: RMS {cv.rms_error:.4f} mm, max |e| {cv.max_abs_error:.4f} mm, "
          f"mean z^2 {cv.mean_squared_z:.2f}")
    z0 = float(np.median(nominal[:, 2]))
    gx, gy = np.meshgrid(np.linspace(nominal[:, 0].min(), nominal[:, 0].max(), 60),
                         np.linspace(nominal[:, 1].min(), nominal[:, 1].max(), 60))
    targets = np.c_[gx.ravel(), gy.ravel(), np.full(gx.size, z0)]
    mean, var = kriging.predict(targets)
    true_rms = np.sqrt(np.mean((mean - true_error(targets)) ** 2))
    print(f"slice z = {z0:.0f} mm: RMS against the simulated truth {true_rms:.4f} mm")

    # 5. The robot pipeline on columns named as the CLI's CSV (q1..q6 deg, x,y,z nominal mm,
    #    mx,my,mz measured mm): a 3-D error vector field, SIMULATED as above per component.
    def measurements(n):
        qq = rng.uniform(0.6 * robot.q_min, 0.6 * robot.q_max, size=(n, 6))
        p = robot.position(qq)
        e = np.c_[true_error(p), 0.5 * true_error(p[:, ::-1]), -0.3 * true_error(p)]
        m = p + e + 0.01 * rng.standard_normal(p.shape)
        cols = {f"q{k + 1}": qq[:, k] for k in range(6)}
        cols.update(x=p[:, 0], y=p[:, 1], z=p[:, 2], mx=m[:, 0], my=m[:, 1], mz=m[:, 2])
        return cols

    train, holdout = measurements(args.samples), measurements(40)
    comp = errfield.fit(train, method="vector-kriging")  # robot=None: the built-in ER20-C10
    print(f"fit: {comp.fit_report['field']}")
    check = errfield.validate(comp, holdout)  # never fitted on these points
    print(check["text"].rstrip())
    send = errfield.compensate(comp, np.column_stack([holdout[f"q{k}"] for k in range(1, 7)]))
    ok = send["status"] == "ok"
    print(f"compensate: {ok.sum()} of {ok.size} targets ok (the others are refused: no joints to send)")

    # 6. Plots.
    fig, ax = plt.subplots(1, 4, figsize=(20, 4.5))
    used = vario.pairs > 0
    h = np.linspace(0, edges[-1], 200)
    ax[0].plot(vario.lag_mean[used], vario.gamma[used], "o", label="empirical")
    ax[0].plot(h, model(h), "-", label="fitted " + model.components[0]["kind"] + " + nugget")
    ax[0].set(xlabel="lag (mm)", ylabel="semivariance (mm²)", title="variogram (SIMULATED data)")
    ax[0].legend(fontsize=7)
    im = ax[1].pcolormesh(gx, gy, mean.reshape(gx.shape), shading="auto", cmap="coolwarm")
    ax[1].set(xlabel="x (mm)", ylabel="y (mm)", title=f"kriged error at z = {z0:.0f} mm (mm)")
    fig.colorbar(im, ax=ax[1])
    im = ax[2].pcolormesh(gx, gy, np.sqrt(var).reshape(gx.shape), shading="auto", cmap="viridis")
    near = np.abs(nominal[:, 2] - z0) < 150
    ax[2].plot(nominal[near, 0], nominal[near, 1], "k.", ms=3)
    ax[2].set(xlabel="x (mm)", ylabel="y (mm)", title="kriging standard deviation (mm)")
    fig.colorbar(im, ax=ax[2])
    points = check["points"]
    bins = np.linspace(0, max(points["before_mm"].max(), points["after_mm"].max()), 20)
    ax[3].hist(points["before_mm"], bins, alpha=0.6, label="nominal robot")
    ax[3].hist(points["after_mm"], bins, alpha=0.6, label="with the model")
    ax[3].set(xlabel="|position error| (mm)", ylabel="held-out points", title="validation (SIMULATED data)")
    ax[3].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
