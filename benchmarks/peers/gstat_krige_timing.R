#!/usr/bin/env Rscript
# Times R gstat's global ordinary kriging (krige, nmax = Inf) with variance on the same kind of
# simulated job as bm_kriging's BM_KrigingDense: N samples uniform in a 1000 mm cube, model
# sph(sill=1, range=300) + nug(0.01), M targets. Prints wall and CPU seconds and the scaled time
# for 100,000 targets (gstat's global kriging is linear in the number of targets).
# Usage: Rscript gstat_krige_timing.R [N=2000] [M=2000]
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
n <- if (length(args) >= 1) as.integer(args[1]) else 2000L
m <- if (length(args) >= 2) as.integer(args[2]) else 2000L
set.seed(1)
s <- data.frame(x = runif(n, 0, 1000), y = runif(n, 0, 1000), z = runif(n, 0, 1000))
s$v <- sin(s$x / 150) * cos(s$y / 200) + 0.0005 * s$z + rnorm(n, 0, 0.01)
t <- data.frame(x = runif(m, 0, 1000), y = runif(m, 0, 1000), z = runif(m, 0, 1000))
model <- vgm(1, "Sph", 300, 0.01)
tm <- system.time(res <- krige(v ~ 1, locations = ~x + y + z, data = s, newdata = t, model = model,
                                debug.level = 0))
cat(sprintf("gstat krige global OK: N = %d, targets = %d: wall %.2f s, cpu %.2f s; scaled to 100000 targets: wall %.0f s, cpu %.0f s\n",
            n, m, tm[["elapsed"]], tm[["user.self"]] + tm[["sys.self"]],
            tm[["elapsed"]] * 1e5 / m, (tm[["user.self"]] + tm[["sys.self"]]) * 1e5 / m))
stopifnot(all(is.finite(res$var1.var)))
