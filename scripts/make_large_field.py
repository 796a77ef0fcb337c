#!/usr/bin/env python3
"""SIMULATED large 3-D error field for the Vecchia likelihood benchmark (docs/kriging.md, "Vecchia
likelihood"): N points uniform in a 1000 mm cube, value = a Gaussian field with an anisotropic
Gaussian covariance (ranges 300, 150, 80 mm along x, y, z; sill 1) drawn by 2,000 random Fourier
features, plus white noise of variance 0.01 (the nugget).

Usage: make_large_field.py N OUT.csv [SEED]
"""
import sys

import numpy as np


def main():
    n = int(sys.argv[1])
    out = sys.argv[2]
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 1000.0, size=(n, 3))
    ranges = np.array([300.0, 150.0, 80.0])
    features = 2000
    # Spectral density of exp(-(h/a)^2): omega ~ N(0, 2 / a^2) per coordinate.
    omega = rng.standard_normal((features, 3)) * np.sqrt(2.0) / ranges
    phase = rng.uniform(0.0, 2.0 * np.pi, features)
    z = np.zeros(n)
    for start in range(0, n, 10000):
        block = x[start:start + 10000]
        z[start:start + 10000] = np.sqrt(2.0 / features) * np.cos(block @ omega.T + phase).sum(axis=1)
    z += rng.normal(0.0, 0.1, n)
    with open(out, "w") as f:
        f.write("# SIMULATED field (scripts/make_large_field.py): gau ranges 300,150,80 mm, sill 1, nugget 0.01, "
                f"seed {seed}\n")
        f.write("x,y,z,v\n")
        for row, value in zip(x, z):
            f.write(f"{row[0]:.4f},{row[1]:.4f},{row[2]:.4f},{value:.6f}\n")


if __name__ == "__main__":
    main()
