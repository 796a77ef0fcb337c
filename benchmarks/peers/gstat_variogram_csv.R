#!/usr/bin/env Rscript
# The whole-process counterpart of `errfield variogram` for timing one process against the other:
# reads a CSV with columns x, y, z, v (as written by gstat_variogram_timing.R), computes gstat's
# sample variogram with 15 bins of width cutoff/15 up to `cutoff` and writes it as CSV to stdout.
#   Rscript benchmarks/peers/gstat_variogram_csv.R /tmp/v20k.csv 100
#   errfield variogram --input /tmp/v20k.csv --coords x,y,z --value v --bins 0:100:6.666666666666667 --convention gstat
# Usage: Rscript gstat_variogram_csv.R CSV [cutoff=100]
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
cutoff <- if (length(args) >= 2) as.numeric(args[2]) else 100
s <- read.csv(args[1])
v <- variogram(v ~ 1, locations = ~x + y + z, data = s, cutoff = cutoff, width = cutoff / 15)
write.csv(data.frame(np = v$np, dist = v$dist, gamma = v$gamma), stdout(), row.names = FALSE)
