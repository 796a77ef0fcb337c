#!/usr/bin/env Rscript
# Times gstat's variogram() on the same kind of simulated data as benchmarks/bm_variogram.cpp
# (N uniform random points in a 2000 mm cube, 3-D, 20 bins up to 2000*sqrt(3)/1.1 mm).
# The data are not bit-identical to the C++ benchmark's (different random generators) but have the
# same size, extent and bins, which is what the pair loop's cost depends on.
#   Rscript scripts/bench_gstat_variogram.R 20000
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
n <- if (length(args) >= 1) as.integer(args[1]) else 20000L
set.seed(42)
ext <- 2000
d <- data.frame(x = runif(n, 0, ext), y = runif(n, 0, ext), z = runif(n, 0, ext))
d$v <- sin(d$x / ext * 3) + cos(d$z / ext * 2) + rnorm(n, 0, 0.01)
coordinates(d) <- ~x + y + z
max_lag <- ext * sqrt(3) / 1.1
b <- seq(0, max_lag, length.out = 21)[-1]
t <- system.time(v <- variogram(v ~ 1, d, boundaries = b))
cat(sprintf("gstat %s variogram(): N = %d, 3-D, %d bins: %.3f s elapsed (%.3f s user), %.0f pairs\n",
            as.character(packageVersion("gstat")), n, length(b), t[["elapsed"]], t[["user.self"]],
            sum(v$np)))
