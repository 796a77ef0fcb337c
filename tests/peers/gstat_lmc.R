#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_lmc_test.cpp: R gstat's direct and cross variograms of a
# multivariable gstat object and its fit.lmc, on the meuse data of the sp package.
#
#   Rscript gstat_lmc.R <out_dir>
#
# Writes
#   meuse.csv     x,y,lzn,lcu,lpb (log zinc, copper, lead)
#   variogram.csv id,np,dist,gamma of variogram(g) (gstat's default bins; ids lzn, lcu, lpb and
#                 the cross ids lzn.lcu, lzn.lpb, lcu.lpb)
#   fit_<m>.csv   id,structure,model,psill,range of fit.lmc(v, g, <model m>), m = sph (vgm(1, "Sph",
#                 800, 1)) and exp (vgm(0.5, "Exp", 300, 0.05)), gstat's defaults otherwise
#                 (fit.ranges = FALSE, fit.method = 7, correct.diagonal = 1).
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 1) stop("usage: gstat_lmc.R out_dir")
out <- args[1]
fmt <- function(df) {  # every number with 17 significant digits
  for (k in names(df)) if (is.numeric(df[[k]])) df[[k]] <- sprintf("%.17g", df[[k]])
  df
}
data(meuse)
write.csv(fmt(data.frame(x = meuse$x, y = meuse$y, lzn = log(meuse$zinc), lcu = log(meuse$copper),
                         lpb = log(meuse$lead))),
          file.path(out, "meuse.csv"), row.names = FALSE, quote = FALSE)
coordinates(meuse) <- ~x + y
g <- gstat(NULL, "lzn", log(zinc) ~ 1, meuse)
g <- gstat(g, "lcu", log(copper) ~ 1, meuse)
g <- gstat(g, "lpb", log(lead) ~ 1, meuse)
v <- variogram(g)
write.csv(fmt(data.frame(id = as.character(v$id), np = v$np, dist = v$dist, gamma = v$gamma)),
          file.path(out, "variogram.csv"), row.names = FALSE, quote = FALSE)
models <- list(sph = vgm(1, "Sph", 800, 1), exp = vgm(0.5, "Exp", 300, 0.05))
for (m in names(models)) {
  f <- fit.lmc(v, g, models[[m]])
  rows <- list()
  for (id in names(f$model)) {
    mm <- f$model[[id]]
    rows[[id]] <- data.frame(id = id, structure = seq_len(nrow(mm)) - 1, model = as.character(mm$model),
                             psill = mm$psill, range = mm$range)
  }
  write.csv(fmt(do.call(rbind, rows)), file.path(out, paste0("fit_", m, ".csv")), row.names = FALSE, quote = FALSE)
}
