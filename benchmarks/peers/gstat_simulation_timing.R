#!/usr/bin/env Rscript
# Times R gstat's conditional Gaussian simulation with a local neighbourhood (krige(nsim = , nmax = ))
# on simulated 2-D data: N samples uniform in a 100 x 100 window, value a smooth field plus noise
# (simulated), targets the nodes of a regular grid of spacing 1 (side x side nodes), model
# sph(sill=1, range=30) + nug(0.05). Prints the wall and CPU seconds of the krige() call alone;
# with a directory, writes samples.csv (x,y,v) and targets.csv (x,y) there first so that
# `errfield interpolate` runs the same job:
#   Rscript benchmarks/peers/gstat_simulation_timing.R 300 100 100 24 /tmp/sim
#   errfield interpolate --method kriging --samples /tmp/sim/samples.csv --targets /tmp/sim/targets.csv \
#       --coords x,y --value v --model "sph(sill=1,range=30)+nug(0.05)" --backend local --neighbors 24 \
#       --simulations 100 --out /tmp/sim/out.csv
# Usage: Rscript gstat_simulation_timing.R [N=300] [side=100] [nsim=100] [nmax=24] [dir]
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
n <- if (length(args) >= 1) as.integer(args[1]) else 300L
side <- if (length(args) >= 2) as.integer(args[2]) else 100L
nsim <- if (length(args) >= 3) as.integer(args[3]) else 100L
nmax <- if (length(args) >= 4) as.integer(args[4]) else 24L
set.seed(7)
s <- data.frame(x = runif(n, 0, 100), y = runif(n, 0, 100))
s$v <- sin(s$x / 15) + cos(s$y / 20) + rnorm(n, 0, 0.2)
g <- expand.grid(x = seq(0.5, side - 0.5, by = 1) * 100 / side, y = seq(0.5, side - 0.5, by = 1) * 100 / side)
if (length(args) >= 5) {
  write.csv(s, file.path(args[5], "samples.csv"), row.names = FALSE)
  write.csv(g, file.path(args[5], "targets.csv"), row.names = FALSE)
}
model <- vgm(1, "Sph", 30, 0.05)
tm <- system.time(res <- krige(v ~ 1, locations = ~x + y, data = s, newdata = g, model = model,
                               nmax = nmax, nsim = nsim, debug.level = 0))
sims <- as.matrix(res[, grep("^sim", names(res))])
cat(sprintf("gstat krige(nsim = %d, nmax = %d): N = %d, %d targets: wall %.2f s, cpu %.2f s; mean of the draws %.4f, variance %.4f\n",
            nsim, nmax, n, nrow(g), tm[["elapsed"]], tm[["user.self"]] + tm[["sys.self"]], mean(sims), mean(apply(sims, 1, var))))
