#!/usr/bin/env Rscript
# Peer reference for the heterotopic cokriging test in tests/peers/gstat_cokriging_test.cpp:
# SIMULATED data (fixed seed): 80 locations in a 100 x 100 square, V measured at all of them, U at
# about 60 % (an empty cell elsewhere in samples.csv). gstat holds each variable with its own data
# set (gstat(id = "V", V ~ 1, all) + gstat(id = "U", U ~ 1, the U subset)), with a given linear
# model of coregionalization (nugget + Sph(40) per direct and cross variogram), and predicts both
# by ordinary cokriging, globally and with maxdist = 35.
# Usage: Rscript gstat_heterotopic.R outdir
# Writes to outdir (numbers with 17 significant digits, an empty cell for "not measured"):
#   samples.csv      x,y,V,U
#   targets.csv      x,y                     60 targets
#   cok.csv          V_pred,V_var,U_pred,U_var,cov   global cokriging
#   cok_local.csv    the same with maxdist = 35
#   direct.csv       id,np,dist,gamma        variogram(g) of the heterotopic gstat object: its direct
#                                            variograms, V over all 80 locations, U over U's own
#   cross.csv        np,dist,gamma           the cross-variogram V.U over the pairs where both are
#                                            measured at both ends (variogram() of the 47-or-so
#                                            collocated samples; gstat's own cross-variogram of the
#                                            heterotopic object is a pseudo cross-variogram)
#   lmc_fit.csv      structure,V,U,V_U       fit.lmc's partial sills (nugget, Sph(40)) fitted to the
#                                            direct variograms above and the collocated cross-variogram
#                                            (fit.ranges = FALSE, fit.method 7), then made PSD
#   cok_fit.csv      as cok.csv, global cokriging with that fitted LMC
# Bins: boundaries 0, 10, ..., 60 (gstat's convention).
suppressPackageStartupMessages({ library(sp); library(gstat) })
out <- commandArgs(trailingOnly = TRUE)[1]
set.seed(20261127)
n <- 80
d <- data.frame(x = runif(n, 0, 100), y = runif(n, 0, 100))
d$V <- sin(d$x / 15) + cos(d$y / 20) + rnorm(n, sd = 0.3)
d$U <- 0.6 * d$V + 0.3 * sin(d$y / 10) + rnorm(n, sd = 0.3)
has_u <- runif(n) < 0.6
t <- data.frame(x = runif(60, -5, 105), y = runif(60, -5, 105))
fmt <- function(v) if (is.numeric(v)) ifelse(is.na(v), "", sprintf("%.17g", v)) else v
put <- function(df, name) {
  df[] <- lapply(df, fmt)
  write.csv(df, file.path(out, name), row.names = FALSE, quote = FALSE)
}
s <- d
s$U[!has_u] <- NA
put(s, "samples.csv")
put(t, "targets.csv")
dv <- d[, c("x", "y", "V")]
du <- d[has_u, c("x", "y", "U")]
coordinates(dv) <- ~x + y
coordinates(du) <- ~x + y
coordinates(t) <- ~x + y
# B_nug = [[0.05, 0.02], [0.02, 0.04]], B_sph = [[0.8, 0.4], [0.4, 0.5]]: both positive definite.
build <- function(maxdist) {
  g <- gstat(NULL, "V", V ~ 1, dv, maxdist = maxdist)
  g <- gstat(g, "U", U ~ 1, du, maxdist = maxdist)
  g <- gstat(g, id = "V", model = vgm(0.8, "Sph", 40, 0.05))
  g <- gstat(g, id = "U", model = vgm(0.5, "Sph", 40, 0.04))
  gstat(g, id = c("V", "U"), model = vgm(0.4, "Sph", 40, 0.02))
}
pick <- function(p) data.frame(V_pred = p$V.pred, V_var = p$V.var, U_pred = p$U.pred, U_var = p$U.var, cov = p$cov.V.U)
put(pick(as.data.frame(predict(build(Inf), t, debug.level = 0))), "cok.csv")
put(pick(as.data.frame(predict(build(35), t, debug.level = 0))), "cok_local.csv")
b <- seq(0, 60, by = 10)
v <- as.data.frame(variogram(build(Inf), boundaries = b))
v <- v[v$id %in% c("V", "U"), ]
put(data.frame(id = as.character(v$id), np = v$np, dist = v$dist, gamma = v$gamma), "direct.csv")
both <- d[has_u, c("x", "y", "V", "U")]
coordinates(both) <- ~x + y
gb <- gstat(NULL, "V", V ~ 1, both)
gb <- gstat(gb, "U", U ~ 1, both)
vb <- as.data.frame(variogram(gb, boundaries = b))
vb <- vb[vb$id == "V.U", ]
put(data.frame(np = vb$np, dist = vb$dist, gamma = vb$gamma), "cross.csv")
# fit.lmc on the heterotopic object's variograms: V and U direct (each over its own data), V.U the
# collocated cross-variogram above (gstat's own V.U of this object is a pseudo cross-variogram).
vh <- variogram(build(Inf), boundaries = b)
vc <- variogram(gb, boundaries = b)
vm <- rbind(vh[vh$id %in% c("V", "U"), ], vc[vc$id == "V.U", ])
vm$id <- factor(as.character(vm$id), levels = c("V.U", "U", "V"))
class(vm) <- class(vh)
g0 <- gstat(NULL, "V", V ~ 1, dv)
g0 <- gstat(g0, "U", U ~ 1, du)
f <- fit.lmc(vm, g0, vgm(1, "Sph", 40, 0.05))
sills <- function(name) f$model[[name]]$psill
put(data.frame(structure = c("nug", "sph"), V = sills("V"), U = sills("U"), V_U = sills("V.U")), "lmc_fit.csv")
# The PSD projection leaves the nugget matrix singular (its cross nugget fitted below -sqrt(V's x U's));
# gstat's legality check (strict Cauchy-Schwarz per structure) refuses that, the kriging system
# itself is positive definite (the Sph matrix is): nocheck = 1 predicts with it.
f$set <- list(nocheck = 1)
put(pick(as.data.frame(predict(f, t, debug.level = 0))), "cok_fit.csv")
