#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_external_drift_test.cpp: kriging with external drift in R
# gstat on the Meuse data that R's sp package ships (meuse: 155 samples, meuse.grid: 3103 cells).
# Usage: Rscript gstat_external_drift.R outdir
# Writes to outdir (numbers with 17 significant digits):
#   meuse.csv      x,y,logzinc,sqrtdist           the samples, log(zinc) and sqrt(dist) as R computes them
#   grid.csv       x,y,sqrtdist                   the targets
#   ked.csv        pred,var   krige(log(zinc) ~ sqrt(dist), model = Sph + nugget), global
#   ked_local.csv  pred,var   the same with nmax = 20
#   uk_ked.csv     pred,var   krige(log(zinc) ~ x + y + sqrt(dist)), Exp + nugget, global
#   anis_local.csv pred,var   krige(log(zinc) ~ sqrt(dist)), Sph + nugget with anis = c(30, 0.5), nmax = 20
#   variogram.csv  np,dist,gamma   variogram(log(zinc) ~ sqrt(dist)), gstat's default bins
#   cv.csv         pred,var,residual   krige.cv(log(zinc) ~ sqrt(dist)), leave-one-out
suppressPackageStartupMessages({ library(sp); library(gstat) })
out <- commandArgs(trailingOnly = TRUE)[1]
data(meuse, package = "sp", envir = environment())
data(meuse.grid, package = "sp", envir = environment())
s <- data.frame(x = meuse$x, y = meuse$y, logzinc = log(meuse$zinc), sqrtdist = sqrt(meuse$dist))
g <- data.frame(x = meuse.grid$x, y = meuse.grid$y, sqrtdist = sqrt(meuse.grid$dist))
fmt <- function(v) sprintf("%.17g", v)
put <- function(df, name) {
  df[] <- lapply(df, fmt)
  write.csv(df, file.path(out, name), row.names = FALSE, quote = FALSE)
}
put(s, "meuse.csv")
put(g, "grid.csv")
sph <- vgm(0.15, "Sph", 800, 0.05)
exp_model <- vgm(0.12, "Exp", 250, 0.04)
k <- krige(logzinc ~ sqrtdist, locations = ~x + y, data = s, newdata = g, model = sph, debug.level = 0)
put(data.frame(pred = k$var1.pred, var = k$var1.var), "ked.csv")
k <- krige(logzinc ~ sqrtdist, locations = ~x + y, data = s, newdata = g, model = sph, nmax = 20, debug.level = 0)
put(data.frame(pred = k$var1.pred, var = k$var1.var), "ked_local.csv")
k <- krige(logzinc ~ x + y + sqrtdist, locations = ~x + y, data = s, newdata = g, model = exp_model, debug.level = 0)
put(data.frame(pred = k$var1.pred, var = k$var1.var), "uk_ked.csv")
anis <- vgm(0.15, "Sph", 800, 0.05, anis = c(30, 0.5))
k <- krige(logzinc ~ sqrtdist, locations = ~x + y, data = s, newdata = g, model = anis, nmax = 20, debug.level = 0)
put(data.frame(pred = k$var1.pred, var = k$var1.var), "anis_local.csv")
sp_s <- s
coordinates(sp_s) <- ~x + y
v <- variogram(logzinc ~ sqrtdist, sp_s)
put(data.frame(np = v$np, dist = v$dist, gamma = v$gamma), "variogram.csv")
cv <- krige.cv(logzinc ~ sqrtdist, sp_s, model = sph, verbose = FALSE)
put(data.frame(pred = cv$var1.pred, var = cv$var1.var, residual = cv$residual), "cv.csv")
