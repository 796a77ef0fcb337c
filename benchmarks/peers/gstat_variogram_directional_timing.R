#!/usr/bin/env Rscript
# Times R gstat's directional sample variogram on simulated 2-D data: N locations uniform in a
# 260 x 300 window (the extent of a typical mining data set), value a smooth field plus noise,
# bins of width cutoff/10 up to `cutoff`, directions alpha (degrees clockwise from +y) with gstat's
# default tolerance 90/length(alpha). Prints the wall and CPU seconds of the variogram() call alone
# and the pairs per direction; with a CSV path, writes the data (columns x,y,v) first so that
# `errfield variogram` can run the same job:
#   Rscript benchmarks/peers/gstat_variogram_directional_timing.R 78000 20 0,45,90,135 /tmp/v78k.csv
#   errfield variogram --input /tmp/v78k.csv --coords x,y --value v --bins 0:20:2 \
#       --convention gstat --alpha 0,45,90,135
# Usage: Rscript gstat_variogram_directional_timing.R [N=78000] [cutoff=20] [alphas=0,45,90,135] [csv]
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
n <- if (length(args) >= 1) as.integer(args[1]) else 78000L
cutoff <- if (length(args) >= 2) as.numeric(args[2]) else 20
alpha <- if (length(args) >= 3) as.numeric(strsplit(args[3], ",")[[1]]) else c(0, 45, 90, 135)
set.seed(42)
s <- data.frame(x = runif(n, 0, 260), y = runif(n, 0, 300))
s$v <- 100 * sin(s$x / 25) + 80 * cos(s$y / 40) + rnorm(n, 0, 5)
if (length(args) >= 4) write.csv(s, args[4], row.names = FALSE)
tm <- system.time(v <- variogram(v ~ 1, locations = ~x + y, data = s, cutoff = cutoff,
                                 width = cutoff / 10, alpha = alpha))
pairs <- tapply(v$np, v$dir.hor, sum)
cat(sprintf("gstat variogram: N = %d, cutoff = %g, alpha = %s: wall %.3f s, cpu %.3f s, pairs per direction %s\n",
            n, cutoff, paste(alpha, collapse = ","), tm[["elapsed"]],
            tm[["user.self"]] + tm[["sys.self"]], paste(pairs, collapse = ",")))
