#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_direction_test.cpp: R gstat's directional empirical
# variograms (alpha, tol.hor, beta, tol.ver) on data the test generates.
#
#   Rscript gstat_direction.R <data.csv> <boundaries "b1,b2,..."> <out_prefix>
#
# data.csv has columns x,y,z,v. Writes, each with columns np,dist,gamma,dir.hor,dir.ver (gstat's
# non-empty bins, directions in the order asked):
#   <out_prefix>_2d_default.csv : x,y; alpha = 0,45,90,135 with gstat's default tol.hor (22.5)
#   <out_prefix>_2d_narrow.csv  : x,y; alpha = 30 and 200, tol.hor = 10
#   <out_prefix>_3d_dip.csv     : x,y,z; alpha = 45, tol.hor = 30, beta = 30 and -20, tol.ver = 20
#   <out_prefix>_3d_flat.csv    : x,y,z; alpha = 45, tol.hor = 30, beta = 0, tol.ver = 20
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 3) stop("usage: gstat_direction.R data.csv b1,b2,... out_prefix")
raw <- read.csv(args[1])
b <- as.numeric(strsplit(args[2], ",")[[1]])
prefix <- args[3]
fmt <- function(v) {  # every number with 17 significant digits
  df <- data.frame(np = v$np, dist = v$dist, gamma = v$gamma, dir.hor = v$dir.hor, dir.ver = v$dir.ver)
  for (k in names(df)) df[[k]] <- sprintf("%.17g", df[[k]])
  df
}
out <- function(v, name) write.csv(fmt(v), paste0(prefix, "_", name, ".csv"), row.names = FALSE, quote = FALSE)
d2 <- raw; coordinates(d2) <- ~x + y
d3 <- raw; coordinates(d3) <- ~x + y + z
out(variogram(v ~ 1, d2, boundaries = b, alpha = c(0, 45, 90, 135)), "2d_default")
out(variogram(v ~ 1, d2, boundaries = b, alpha = c(30, 200), tol.hor = 10), "2d_narrow")
out(variogram(v ~ 1, d3, boundaries = b, alpha = 45, tol.hor = 30, beta = c(30, -20), tol.ver = 20), "3d_dip")
out(variogram(v ~ 1, d3, boundaries = b, alpha = 45, tol.hor = 30, beta = 0, tol.ver = 20), "3d_flat")
