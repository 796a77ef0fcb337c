#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_krige_test.cpp (GstatNeighbourhood): R gstat's krige() with
# the neighbourhood and block settings a day-two gstat user reaches for, on 2-D data.
# Usage: Rscript gstat_neighbourhood.R samples.csv targets.csv cases.tsv out.csv
#   samples.csv: x,y,v      targets.csv: x,y
#   cases.tsv (tab-separated, header case model maxdist nmax nmin omax block nblockdiscr):
#     model        gstat vgm call, e.g. vgm(1, 'Sph', 6, 0.1)
#     maxdist      gstat's maxdist (Inf = none); nmax (Inf = all); nmin, omax (0 = none)
#     block        "none", or the block size "DX DY"
#     nblockdiscr  0 = gstat's default (Gauss), else a regular N x N discretization
#   Ordinary kriging (v ~ 1) throughout.
# Writes out.csv: case,target,pred,var (17 significant digits; NA where gstat gives none).
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
samples <- read.csv(args[1])
targets <- read.csv(args[2])
cases <- read.delim(args[3], stringsAsFactors = FALSE)
rows <- list()
for (k in seq_len(nrow(cases))) {
  cs <- cases[k, ]
  block <- if (cs$block == "none") numeric(0) else as.numeric(strsplit(cs$block, " ")[[1]])
  set <- if (cs$nblockdiscr > 0) list(nblockdiscr = cs$nblockdiscr) else list()
  res <- krige(v ~ 1, locations = ~x + y, data = samples, newdata = targets,
               model = eval(parse(text = cs$model)), maxdist = as.numeric(cs$maxdist),
               nmax = as.numeric(cs$nmax), nmin = cs$nmin, omax = cs$omax, block = block, set = set,
               debug.level = 0)
  rows[[k]] <- data.frame(case = cs$case, target = seq_len(nrow(targets)) - 1,
                          pred = sprintf("%.17g", res$var1.pred), var = sprintf("%.17g", res$var1.var))
}
write.csv(do.call(rbind, rows), args[4], row.names = FALSE, quote = FALSE)
