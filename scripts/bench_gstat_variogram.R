#!/usr/bin/env Rscript
# Times gstat's variogram() on simulated data like benchmarks/bm_variogram.cpp's (N uniform random
# points in a 2000 mm cube, 3-D, 20 bins of equal width up to 2000*sqrt(3)/1.1 mm), and writes the
# same data to a CSV so that `errfield variogram` can be timed on identical input:
#
#   Rscript scripts/bench_gstat_variogram.R 20000 /tmp/bench.csv
#   # prints the gstat time and the matching errfield command line
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
n <- if (length(args) >= 1) as.integer(args[1]) else 20000L
out_csv <- if (length(args) >= 2) args[2] else ""
set.seed(42)
ext <- 2000
d <- data.frame(x = runif(n, 0, ext), y = runif(n, 0, ext), z = runif(n, 0, ext))
d$v <- sin(d$x / ext * 3) + cos(d$z / ext * 2) + rnorm(n, 0, 0.01)
if (nzchar(out_csv)) {
  w <- d
  for (k in names(w)) w[[k]] <- sprintf("%.17g", w[[k]])
  write.csv(w, out_csv, row.names = FALSE, quote = FALSE)
}
coordinates(d) <- ~x + y + z
max_lag <- ext * sqrt(3) / 1.1
b <- seq(0, max_lag, length.out = 21)[-1]
t <- system.time(v <- variogram(v ~ 1, d, boundaries = b))
cat(sprintf("gstat %s variogram(): N = %d, 3-D, %d bins: %.3f s elapsed (%.3f s user), %.0f pairs\n",
            as.character(packageVersion("gstat")), n, length(b), t[["elapsed"]], t[["user.self"]],
            sum(v$np)))
if (nzchar(out_csv))
  cat(sprintf("errfield variogram --input %s --coords x,y,z --value v --convention gstat --bins 0,%s\n",
              out_csv, paste(sprintf("%.17g", b), collapse = ",")))
