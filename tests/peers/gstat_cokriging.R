#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_cokriging_test.cpp: ordinary cokriging of log(zinc) and
# log(copper) in R gstat on the Meuse data that R's sp package ships (155 samples, 3103 grid cells),
# with an explicit linear model of coregionalization (nugget + Sph(800) per direct and cross
# variogram; both coregionalization matrices positive definite). gstat's multivariable predict()
# is ordinary cokriging with one unknown mean per variable.
# Usage: Rscript gstat_cokriging.R outdir
# Writes to outdir (numbers with 17 significant digits):
#   meuse.csv        x,y,lzn,lcu                          the samples
#   grid.csv         x,y                                  the targets
#   cok.csv          lzn_pred,lzn_var,lcu_pred,lcu_var,cov   global cokriging
#   cok_local.csv    the same with nmax = 20
#   cok_universal.csv   global universal cokriging, a linear drift in x and y per variable
#   cv.csv           lzn_pred,lzn_var,lzn_residual,lcu_residual   gstat.cv(remove.all = TRUE): leave-one-out
#                    with every variable of a sample left out (gstat reports pred and var of the first)
suppressPackageStartupMessages({ library(sp); library(gstat) })
out <- commandArgs(trailingOnly = TRUE)[1]
data(meuse, package = "sp", envir = environment())
data(meuse.grid, package = "sp", envir = environment())
s <- data.frame(x = meuse$x, y = meuse$y, lzn = log(meuse$zinc), lcu = log(meuse$copper))
g <- data.frame(x = meuse.grid$x, y = meuse.grid$y)
fmt <- function(v) sprintf("%.17g", v)
put <- function(df, name) {
  df[] <- lapply(df, fmt)
  write.csv(df, file.path(out, name), row.names = FALSE, quote = FALSE)
}
put(s, "meuse.csv")
put(g, "grid.csv")
coordinates(s) <- ~x + y
coordinates(g) <- ~x + y
# B_nug = [[0.05, 0.02], [0.02, 0.04]], B_sph = [[0.55, 0.25], [0.25, 0.15]]: both positive definite.
build <- function(nmax, drift = "1") {
  m <- gstat(NULL, "lzn", as.formula(paste("lzn ~", drift)), s, nmax = nmax)
  m <- gstat(m, "lcu", as.formula(paste("lcu ~", drift)), s, nmax = nmax)
  m <- gstat(m, id = "lzn", model = vgm(0.55, "Sph", 800, 0.05))
  m <- gstat(m, id = "lcu", model = vgm(0.15, "Sph", 800, 0.04))
  gstat(m, id = c("lzn", "lcu"), model = vgm(0.25, "Sph", 800, 0.02))
}
pick <- function(p) data.frame(lzn_pred = p$lzn.pred, lzn_var = p$lzn.var, lcu_pred = p$lcu.pred,
                               lcu_var = p$lcu.var, cov = p$cov.lzn.lcu)
put(pick(as.data.frame(predict(build(Inf), g, debug.level = 0))), "cok.csv")
put(pick(as.data.frame(predict(build(20), g, debug.level = 0))), "cok_local.csv")
put(pick(as.data.frame(predict(build(Inf, "x + y"), g, debug.level = 0))), "cok_universal.csv")
cv <- as.data.frame(gstat.cv(build(Inf), remove.all = TRUE, verbose = FALSE))
all <- as.data.frame(gstat.cv(build(Inf), remove.all = TRUE, verbose = FALSE, all.residuals = TRUE))
put(data.frame(lzn_pred = cv$lzn.pred, lzn_var = cv$lzn.var, lzn_residual = all$lzn, lcu_residual = all$lcu), "cv.csv")
