#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_krige_test.cpp: kriging with R gstat's krige().
# Usage: Rscript gstat_krige.R samples.csv targets.csv cases.csv out.csv
#   samples.csv: x,y,z,v      targets.csv: x,y,z
#   cases.csv (tab-separated, header case<TAB>model<TAB>formula<TAB>nmax<TAB>beta):
#     model   gstat vgm call, e.g. vgm(0.5, 'Sph', 60, 0.02)
#     formula v ~ 1 (simple/ordinary), v ~ x + y + z (universal order 1), ...
#     nmax    Inf for global kriging, else gstat's nmax (nearest samples per target)
#     beta    simple kriging mean, or NA for ordinary/universal
# Writes out.csv: case,target,pred,var (17 significant digits).
suppressPackageStartupMessages(library(gstat))
args <- commandArgs(trailingOnly = TRUE)
samples <- read.csv(args[1])
targets <- read.csv(args[2])
cases <- read.delim(args[3], stringsAsFactors = FALSE)
rows <- list()
for (k in seq_len(nrow(cases))) {
  cs <- cases[k, ]
  model <- eval(parse(text = cs$model))
  formula <- as.formula(cs$formula)
  nmax <- as.numeric(cs$nmax)
  if (is.na(cs$beta)) {
    res <- krige(formula, locations = ~x + y + z, data = samples, newdata = targets, model = model,
                 nmax = nmax, debug.level = 0)
  } else {
    res <- krige(formula, locations = ~x + y + z, data = samples, newdata = targets, model = model,
                 nmax = nmax, beta = as.numeric(cs$beta), debug.level = 0)
  }
  rows[[k]] <- data.frame(case = cs$case, target = seq_len(nrow(targets)) - 1,
                          pred = sprintf("%.17g", res$var1.pred), var = sprintf("%.17g", res$var1.var))
}
write.csv(do.call(rbind, rows), args[4], row.names = FALSE, quote = FALSE)
