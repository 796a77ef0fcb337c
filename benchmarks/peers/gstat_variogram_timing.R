#!/usr/bin/env Rscript
# Times R gstat's sample variogram on the job of bm_variogram's BM_VariogramCutoff3d: N locations
# uniform in a 500 cube (simulated), 15 bins of width cutoff/15 up to `cutoff`. Prints the wall and
# CPU seconds of the variogram() call alone, the number of binned pairs, and - when a CSV path is
# given - writes the data (columns x,y,z,v) so that `errfield variogram` can run the same job:
#   Rscript benchmarks/peers/gstat_variogram_timing.R 20000 100 /tmp/v20k.csv
#   errfield variogram --input /tmp/v20k.csv --coords x,y,z --value v --bins 0:100:6.666666666666667 --convention gstat
# Usage: Rscript gstat_variogram_timing.R [N=20000] [cutoff=100] [csv]
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
n <- if (length(args) >= 1) as.integer(args[1]) else 20000L
cutoff <- if (length(args) >= 2) as.numeric(args[2]) else 100
set.seed(42)
s <- data.frame(x = runif(n, 0, 500), y = runif(n, 0, 500), z = runif(n, 0, 500))
s$v <- sin(s$x / 80) + cos(s$z / 120) + rnorm(n, 0, 0.01)
if (length(args) >= 3) write.csv(s, args[3], row.names = FALSE)
tm <- system.time(v <- variogram(v ~ 1, locations = ~x + y + z, data = s, cutoff = cutoff,
                                 width = cutoff / 15))
cat(sprintf("gstat variogram: N = %d, cutoff = %g: wall %.3f s, cpu %.3f s, %.0f binned pairs in %d bins\n",
            n, cutoff, tm[["elapsed"]], tm[["user.self"]] + tm[["sys.self"]], sum(v$np), nrow(v)))
